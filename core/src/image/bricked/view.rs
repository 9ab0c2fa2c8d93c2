//! [`BrickedView`]: the validated index of a bricked scene, borrowed in place.

use glam::Vec3;

use super::error::BrickedError;
use super::layout::{BrickRecord, BrickedHeader, Codec, BRICKED_MAGIC, BRICKED_VERSION, INDEX_CHECKSUM_OFFSET};
use crate::image::crc32::crc32_with_hole;
use crate::image::limits::{IMAGE_ALIGN, MAX_TREE_DEPTH};
use crate::image::records::BvhNode;
use crate::image::sections::finite3;
use crate::image::structure_views::BvhView;
use crate::image::validate::tree::{pair, validate_tree, Children};
use crate::image::SceneView;
use crate::probe::MemoryProbe;

/// The largest brick: a brick is a flat scene image, whose sizes are 32-bit.
const MAX_BRICK_IMAGE: u64 = u32::MAX as u64;

/// A validated bricked index. Cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct BrickedView<'a> {
    header: &'a BrickedHeader,
    bricks: &'a [BrickRecord],
    top: BvhView<'a>,
    globals: SceneView<'a>,
    codec: Codec,
}

/// `a` rounded up to a multiple of 64.
fn align64(a: u64) -> u64 {
    a.div_ceil(64).saturating_mul(64)
}

impl<'a> BrickedView<'a> {
    /// Validates the index at the start of `bytes` (16-byte aligned; it may hold the
    /// whole file or only the index) for a file of `file_len` bytes: magic, version,
    /// checksum, the directory (every brick inside the file, after the index, in file
    /// order, none overlapping), the top-level tree (bounded depth, leaves naming real
    /// bricks) and the globals image. The bricks themselves are checked one by one as
    /// they are loaded ([`BrickedView::check_brick`]).
    pub fn parse(bytes: &'a [u8], file_len: u64) -> Result<BrickedView<'a>, BrickedError> {
        let len = bytes.len() as u64;
        let head = bytes.get(..128).ok_or(BrickedError::Truncated { needed: 128, len })?;
        if !(bytes.as_ptr() as usize).is_multiple_of(IMAGE_ALIGN) {
            return Err(BrickedError::Misaligned);
        }
        let header: &BrickedHeader = bytemuck::try_from_bytes(head).map_err(|_| BrickedError::Misaligned)?;
        if header.magic != BRICKED_MAGIC {
            return Err(BrickedError::BadMagic);
        }
        if header.version != BRICKED_VERSION {
            return Err(BrickedError::UnsupportedVersion(header.version));
        }
        if header.flags != 0 || header.reserved != [0; 2] {
            return Err(BrickedError::Reserved);
        }
        let codec = Codec::from_u32(header.codec).ok_or(BrickedError::UnknownCodec(header.codec))?;
        let index_size = header.index_size;
        if index_size < 128 || !index_size.is_multiple_of(64) || index_size > header.total_size {
            return Err(BrickedError::BadLayout);
        }
        if header.total_size != file_len {
            return Err(BrickedError::Truncated { needed: header.total_size, len: file_len });
        }
        let index_len = usize::try_from(index_size).map_err(|_| BrickedError::BadLayout)?;
        let index = bytes.get(..index_len).ok_or(BrickedError::Truncated { needed: index_size, len })?;
        let computed = crc32_with_hole(index, INDEX_CHECKSUM_OFFSET);
        if computed != header.index_checksum {
            return Err(BrickedError::ChecksumMismatch { stored: header.index_checksum, computed });
        }
        let (bricks, top, list_end) = Self::parts(header, index)?;
        if header.globals_offset != align64(list_end)
            || header.globals_offset.saturating_add(header.globals_size) > index_size
            || align64(header.globals_offset + header.globals_size) != index_size
        {
            return Err(BrickedError::BadLayout);
        }
        let globals = &index[header.globals_offset as usize..(header.globals_offset + header.globals_size) as usize];
        let globals = SceneView::parse(globals).map_err(BrickedError::Globals)?;
        if globals.triangle_count() != 0 {
            return Err(BrickedError::BadLayout);
        }
        Self::check_directory(header, bricks)?;
        Self::check_tree(header, &top)?;
        Ok(BrickedView { header, bricks, top, globals, codec })
    }

    /// The directory, the top-level tree and where the list ends, cut from the index.
    fn parts(header: &BrickedHeader, index: &'a [u8]) -> Result<(&'a [BrickRecord], BvhView<'a>, u64), BrickedError> {
        let nb = header.brick_count as u64;
        let dir_end = 128 + 64 * nb;
        let nodes_end = dir_end + 32 * header.node_count as u64;
        let list_end = nodes_end + 4 * nb;
        if list_end > index.len() as u64 || nb == 0 || header.node_count == 0 {
            return Err(BrickedError::BadLayout);
        }
        let cut = |a: u64, b: u64| &index[a as usize..b as usize];
        let bricks: &[BrickRecord] =
            bytemuck::try_cast_slice(cut(128, dir_end)).map_err(|_| BrickedError::BadLayout)?;
        let nodes: &[BvhNode] =
            bytemuck::try_cast_slice(cut(dir_end, nodes_end)).map_err(|_| BrickedError::BadLayout)?;
        let prims: &[u32] = bytemuck::try_cast_slice(cut(nodes_end, list_end)).map_err(|_| BrickedError::BadLayout)?;
        // Probe addresses of the top level are offsets in the index (which fits 32 bits
        // unless the directory alone passes 4 GiB; they are labels, never dereferenced).
        let top = BvhView { nodes, prims, nodes_addr: dir_end as u32, prims_addr: nodes_end as u32 };
        Ok((bricks, top, list_end))
    }

    /// Every brick inside the file, after the index, in file order without overlap, of
    /// a possible size and with ordered finite bounds; the counts adding up.
    fn check_directory(header: &BrickedHeader, bricks: &[BrickRecord]) -> Result<(), BrickedError> {
        let mut end = header.index_size;
        let mut triangles = 0u64;
        let mut largest = 0u64;
        for (i, b) in bricks.iter().enumerate() {
            let brick = i as u32;
            let stop = b.offset.checked_add(b.stored_size).ok_or(BrickedError::BrickOutOfPlace { brick })?;
            if b.offset < end || stop > header.total_size || b.stored_size == 0 {
                return Err(BrickedError::BrickOutOfPlace { brick });
            }
            end = stop;
            let ordered = finite3(b.bounds_min)
                && finite3(b.bounds_max)
                && Vec3::from(b.bounds_min).cmple(Vec3::from(b.bounds_max)).all();
            // Stored bytes beyond the image's size and a codec's worst-case growth are not
            // a compressed image (and would have a reader allocate for nothing).
            let stored_ok = b.stored_size <= b.image_size + b.image_size / 16 + 4096;
            if b.image_size < 64
                || b.image_size > MAX_BRICK_IMAGE
                || b.triangle_count == 0
                || !ordered
                || !stored_ok
                || b.reserved != 0
            {
                return Err(BrickedError::BadBrick { brick });
            }
            triangles += b.triangle_count as u64;
            largest = largest.max(b.image_size);
        }
        if triangles != header.reference_count
            || header.triangle_count == 0
            || header.triangle_count > header.reference_count
        {
            return Err(BrickedError::CountMismatch);
        }
        if largest != header.max_brick_size {
            return Err(BrickedError::BadLayout);
        }
        Ok(())
    }

    /// The top-level BVH: a tree of finite ordered boxes, at most [`MAX_TREE_DEPTH`]
    /// deep, whose leaves' list entries name existing bricks.
    fn check_tree(header: &BrickedHeader, top: &BvhView<'_>) -> Result<(), BrickedError> {
        let nb = header.brick_count;
        // A list entry naming no brick is reported at the root: entries have no owner
        // until the tree is walked.
        if top.prims.iter().any(|&b| b >= nb) {
            return Err(BrickedError::BadTree { node: 0 });
        }
        let nodes = top.nodes;
        validate_tree(nodes.len(), crate::image::SectionKind::BvhNodes, MAX_TREE_DEPTH, nb as u64, |i| {
            let n = nodes.get(i).ok_or(())?;
            let ordered = Vec3::from(n.min).cmple(Vec3::from(n.max)).all();
            if !(finite3(n.min) && finite3(n.max) && ordered) {
                return Err(());
            }
            if n.count == 0 {
                Ok((pair(n.first), 0))
            } else if n.first as u64 + n.count as u64 <= nb as u64 {
                Ok((Children::new(), n.count as u64))
            } else {
                Err(())
            }
        })
        .map_err(|e| match e {
            crate::image::SceneError::BadTree { node, .. } => BrickedError::BadTree { node },
            _ => BrickedError::BadTree { node: 0 },
        })
    }

    /// Checks a loaded brick's decompressed image against its directory record: its size
    /// and triangle count, its bounds inside the record's, and scene-wide triangle ids
    /// (TRIANGLE_IDS, strictly increasing as `parse` checked) below the scene's count.
    /// `stored_checksum` is the CRC-32 the driver computed over the stored bytes.
    pub fn check_brick(
        &self,
        brick: u32,
        stored_checksum: u32,
        image: &'a [u8],
    ) -> Result<SceneView<'a>, BrickedError> {
        let rec = self.brick(brick).ok_or(BrickedError::BadBrick { brick })?;
        if stored_checksum != rec.checksum {
            return Err(BrickedError::BrickChecksum { brick });
        }
        if image.len() as u64 != rec.image_size {
            return Err(BrickedError::BrickMismatch { brick });
        }
        let view = SceneView::parse(image).map_err(|error| BrickedError::BrickImage { brick, error })?;
        let (lo, hi) = (Vec3::from(view.header().bounds_min), Vec3::from(view.header().bounds_max));
        let inside = lo.cmpge(Vec3::from(rec.bounds_min)).all() && hi.cmple(Vec3::from(rec.bounds_max)).all();
        let last_id = view.scene_triangle_id(view.triangle_count().wrapping_sub(1));
        if view.triangle_count() != rec.triangle_count
            || !view.is_brick()
            || !inside
            || last_id as u64 >= self.header.triangle_count
        {
            return Err(BrickedError::BrickMismatch { brick });
        }
        Ok(view)
    }

    /// The header.
    pub fn header(&self) -> &'a BrickedHeader {
        self.header
    }

    /// The codec the bricks are stored with.
    pub fn codec(&self) -> Codec {
        self.codec
    }

    /// Number of bricks.
    pub fn brick_count(&self) -> u32 {
        self.bricks.len() as u32
    }

    /// Brick `b`'s directory record.
    pub fn brick(&self, b: u32) -> Option<&'a BrickRecord> {
        self.bricks.get(b as usize)
    }

    /// Every directory record.
    pub fn bricks(&self) -> &'a [BrickRecord] {
        self.bricks
    }

    /// The top-level BVH over the bricks (its leaves' list entries are brick ids).
    pub fn top(&self) -> &BvhView<'a> {
        &self.top
    }

    /// The globals image: the scene's camera and its lights (no triangles), which
    /// shades what misses every brick.
    pub fn globals(&self) -> &SceneView<'a> {
        &self.globals
    }

    /// Reads top-level list entry `pos`: a brick id.
    #[inline]
    pub fn list_brick<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        self.top.prim(pos, probe)
    }
}

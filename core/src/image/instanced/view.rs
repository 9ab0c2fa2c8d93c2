//! [`InstancedView`]: a validated instanced scene file, borrowed in place.

use glam::Vec3;

use super::error::InstancedError;
use super::layout::{
    BottomRecord, InstanceRecord, InstancedHeader, INSTANCED_CHECKSUM_OFFSET, INSTANCED_MAGIC, INSTANCED_VERSION,
};
use super::top_level::{TopLevel, TopParts};
use crate::image::crc32::crc32_with_hole;
use crate::image::limits::IMAGE_ALIGN;
use crate::image::records::BvhNode;
use crate::image::sections::finite3;
use crate::image::SceneView;

/// A validated instanced scene. Cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct InstancedView<'a> {
    header: &'a InstancedHeader,
    bytes: &'a [u8],
    bottoms: &'a [BottomRecord],
    top: TopLevel<'a>,
    globals: SceneView<'a>,
}

fn align64(a: u64) -> u64 {
    a.div_ceil(64).saturating_mul(64)
}

impl<'a> InstancedView<'a> {
    /// Validates the file in `bytes` (64-byte aligned; it may be longer): magic,
    /// version, the index's checksum, the layout, the bottom directory (every image
    /// inside the file, after the index, 64-byte aligned, in file order, none
    /// overlapping), the instances and the top-level tree ([`TopLevel::new`]) and the
    /// globals image. The bottom images are validated one by one with
    /// [`InstancedView::bottom`], once, by the driver that keeps their views.
    pub fn parse(bytes: &'a [u8]) -> Result<InstancedView<'a>, InstancedError> {
        let len = bytes.len() as u64;
        let head = bytes.get(..128).ok_or(InstancedError::Truncated { needed: 128, len })?;
        if !(bytes.as_ptr() as usize).is_multiple_of(IMAGE_ALIGN) {
            return Err(InstancedError::Misaligned);
        }
        let header: &InstancedHeader = bytemuck::try_from_bytes(head).map_err(|_| InstancedError::Misaligned)?;
        if header.magic != INSTANCED_MAGIC {
            return Err(InstancedError::BadMagic);
        }
        if header.version != INSTANCED_VERSION {
            return Err(InstancedError::UnsupportedVersion(header.version));
        }
        if header.flags != 0 || header.reserved != [0; 6] {
            return Err(InstancedError::Reserved);
        }
        if header.total_size > len {
            return Err(InstancedError::Truncated { needed: header.total_size, len });
        }
        let index_size = header.index_size;
        if index_size < 128 || !index_size.is_multiple_of(64) || index_size > header.total_size {
            return Err(InstancedError::BadLayout);
        }
        let bytes = &bytes[..header.total_size as usize];
        let index = &bytes[..index_size as usize];
        let computed = crc32_with_hole(index, INSTANCED_CHECKSUM_OFFSET);
        if computed != header.index_checksum {
            return Err(InstancedError::ChecksumMismatch { stored: header.index_checksum, computed });
        }
        let (instances, bottoms, nodes, list, addrs, list_end) = Self::parts(header, index)?;
        if header.globals_offset != align64(list_end)
            || header.globals_offset.saturating_add(header.globals_size) > index_size
            || align64(header.globals_offset + header.globals_size) != index_size
        {
            return Err(InstancedError::BadLayout);
        }
        let globals = &index[header.globals_offset as usize..(header.globals_offset + header.globals_size) as usize];
        let globals = SceneView::parse(globals).map_err(InstancedError::Globals)?;
        if globals.triangle_count() != 0 {
            return Err(InstancedError::BadLayout);
        }
        Self::check_directory(header, bottoms)?;
        let bounds = |b: u32| bottoms.get(b as usize).map(|r| (Vec3::from(r.bounds_min), Vec3::from(r.bounds_max)));
        let parts = TopParts { instances, nodes, list, addrs };
        let top = TopLevel::new(parts, bounds, globals.materials().len() as u32)?;
        Self::check_counts(header, bottoms, instances)?;
        Ok(InstancedView { header, bytes, bottoms, top, globals })
    }

    /// The instances, the bottom directory, the nodes, the list, their addresses and
    /// where the list ends, cut from the index.
    #[allow(clippy::type_complexity)]
    fn parts(
        header: &InstancedHeader,
        index: &'a [u8],
    ) -> Result<(&'a [InstanceRecord], &'a [BottomRecord], &'a [BvhNode], &'a [u32], [u32; 3], u64), InstancedError>
    {
        let (ni, nb, nn) = (header.instance_count, header.bottom_count, header.node_count);
        let (addrs, list_end) = super::layout::index_layout(ni, nb, nn);
        if list_end > index.len() as u64 || ni == 0 || nb == 0 || nn == 0 {
            return Err(InstancedError::BadLayout);
        }
        // Below the index's length, so no label wrapped.
        let (dir_at, nodes_at, list_at) = (128 + 128 * ni as u64, addrs[1] as u64, addrs[2] as u64);
        let cut = |a: u64, b: u64| &index[a as usize..b as usize];
        let bad = |_| InstancedError::BadLayout;
        let instances: &[InstanceRecord] = bytemuck::try_cast_slice(cut(128, dir_at)).map_err(bad)?;
        let bottoms: &[BottomRecord] = bytemuck::try_cast_slice(cut(dir_at, nodes_at)).map_err(bad)?;
        let nodes: &[BvhNode] = bytemuck::try_cast_slice(cut(nodes_at, list_at)).map_err(bad)?;
        let list: &[u32] = bytemuck::try_cast_slice(cut(list_at, list_end)).map_err(bad)?;
        // The index is below 4 GiB whenever these fit; probe addresses are labels.
        Ok((instances, bottoms, nodes, list, addrs, list_end))
    }

    /// Every bottom image after the index, 64-byte aligned, in file order without
    /// overlap, of a possible size, with finite ordered bounds.
    fn check_directory(header: &InstancedHeader, bottoms: &[BottomRecord]) -> Result<(), InstancedError> {
        let mut end = header.index_size;
        for (i, b) in bottoms.iter().enumerate() {
            let bottom = i as u32;
            let stop = b.offset.checked_add(b.size).ok_or(InstancedError::BottomOutOfPlace { bottom })?;
            if b.offset < end || !b.offset.is_multiple_of(64) || stop > header.total_size {
                return Err(InstancedError::BottomOutOfPlace { bottom });
            }
            end = stop;
            let ordered = finite3(b.bounds_min)
                && finite3(b.bounds_max)
                && Vec3::from(b.bounds_min).cmple(Vec3::from(b.bounds_max)).all();
            if b.size < 64 || b.size > u32::MAX as u64 || !ordered || b.reserved != [0; 3] {
                return Err(InstancedError::BadBottom { bottom });
            }
        }
        Ok(())
    }

    /// The header's counts: instances' triangles and the bottoms' stored triangles.
    fn check_counts(
        header: &InstancedHeader,
        bottoms: &[BottomRecord],
        instances: &[InstanceRecord],
    ) -> Result<(), InstancedError> {
        let stored: u64 = bottoms.iter().map(|b| b.triangle_count as u64).sum();
        let drawn: u64 =
            instances.iter().map(|i| bottoms.get(i.bottom as usize).map_or(0, |b| b.triangle_count as u64)).sum();
        if stored != header.stored_triangles || drawn != header.triangle_count {
            return Err(InstancedError::CountMismatch);
        }
        Ok(())
    }

    /// Validates bottom image `b` ([`SceneView::parse`]) and checks it against its
    /// directory record (triangles, vertices, structure, bounds). A driver does this once
    /// per bottom and keeps the views, e.g. in an array indexed by bottom id.
    pub fn bottom(&self, b: u32) -> Result<SceneView<'a>, InstancedError> {
        let rec = self.bottoms.get(b as usize).ok_or(InstancedError::BadBottom { bottom: b })?;
        let image = self.bytes.get(rec.offset as usize..(rec.offset + rec.size) as usize);
        let image = image.ok_or(InstancedError::BottomOutOfPlace { bottom: b })?;
        let view = SceneView::parse(image).map_err(|error| InstancedError::BottomImage { bottom: b, error })?;
        let h = view.header();
        if h.triangle_count != rec.triangle_count
            || h.vertex_count != rec.vertex_count
            || h.accel != rec.accel
            || h.total_size as u64 != rec.size
            || h.bounds_min != rec.bounds_min
            || h.bounds_max != rec.bounds_max
        {
            return Err(InstancedError::BottomMismatch { bottom: b });
        }
        Ok(view)
    }

    /// The header.
    pub fn header(&self) -> &'a InstancedHeader {
        self.header
    }

    /// The top level: instances and the BVH over them.
    pub fn top(&self) -> &TopLevel<'a> {
        &self.top
    }

    /// Number of bottom images.
    pub fn bottom_count(&self) -> u32 {
        self.bottoms.len() as u32
    }

    /// Every bottom directory record.
    pub fn bottoms(&self) -> &'a [BottomRecord] {
        self.bottoms
    }

    /// The globals image: camera, lights and the instances' override materials (no
    /// triangles); it shades what misses every instance.
    pub fn globals(&self) -> &SceneView<'a> {
        &self.globals
    }

    /// The world bounds.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (Vec3::from(self.header.bounds_min), Vec3::from(self.header.bounds_max))
    }
}

//! One triangle as the bricked build carries it from the input to its brick: its three
//! vertices (welded again inside the brick), its scene-wide id, material and object, and
//! its vertices' shading data. Spill files hold these records back to back.

use bytemuck::{Pod, Zeroable};
use raypipe_core::image::{ShadingVertex, NULL_INDEX};

/// A triangle on its way to a brick.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct TriRecord {
    /// The three vertex positions.
    pub p: [[f32; 3]; 3],
    /// Scene-wide id: the triangle's index in the input's face order.
    pub id: u32,
    /// Material index ([`NULL_INDEX`] without materials).
    pub material: u32,
    /// Object id.
    pub object: u32,
    /// The vertices' shading data (zero when the scene has none; not spilled then).
    pub shading: [ShadingVertex; 3],
}

/// Bytes of a record without shading data, as spilled for a scene that has none.
pub const COMPACT_BYTES: usize = 48;
/// Bytes of a full record.
pub const FULL_BYTES: usize = std::mem::size_of::<TriRecord>();
const _: () = assert!(FULL_BYTES == 144);

impl TriRecord {
    /// A record without material, object or shading data.
    pub fn plain(p: [[f32; 3]; 3], id: u32) -> TriRecord {
        TriRecord { p, id, material: NULL_INDEX, object: 0, shading: [ShadingVertex::zeroed(); 3] }
    }

    /// The centroid on `axis` (the partition's sort key), in f64 so that the three
    /// coordinates sum exactly enough to order triangles the same way everywhere.
    #[inline]
    pub fn centroid(&self, axis: usize) -> f64 {
        (f64::from(self.p[0][axis]) + f64::from(self.p[1][axis]) + f64::from(self.p[2][axis])) / 3.0
    }

    /// The bytes spilled for this record: all of them, or the first
    /// [`COMPACT_BYTES`] when the scene has no shading data.
    pub fn spilled(&self, shading: bool) -> &[u8] {
        let b = bytemuck::bytes_of(self);
        if shading {
            b
        } else {
            &b[..COMPACT_BYTES]
        }
    }

    /// A record read back from its spilled bytes.
    pub fn from_spilled(bytes: &[u8]) -> TriRecord {
        let mut r = TriRecord::zeroed();
        let n = bytes.len().min(FULL_BYTES);
        bytemuck::bytes_of_mut(&mut r)[..n].copy_from_slice(&bytes[..n]);
        r
    }
}

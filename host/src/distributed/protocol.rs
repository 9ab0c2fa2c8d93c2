//! The messages between the master and the workers, as bytes: fixed little-endian
//! headers (`bytemuck` records) and, for a rendered tile, its colours. Decoding checks
//! every length, so a malformed message is an error, never a panic.

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Worker → master, once: loaded and ready, with where it runs (or not: the message
/// says why).
pub const TAG_READY: i32 = 1;
/// Master → worker: render this tile of this frame.
pub const TAG_ASSIGN: i32 = 2;
/// Worker → master: a rendered tile.
pub const TAG_TILE: i32 = 3;
/// Master → worker: no more work; leave.
pub const TAG_STOP: i32 = 4;

/// A tile to render.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct Assign {
    /// Frame of the walk (0 for a single image).
    pub frame: u32,
    /// Tile index in the frame's tile list.
    pub tile: u32,
}

/// The header of a rendered tile.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct TileHeader {
    /// Frame of the walk.
    pub frame: u32,
    /// Tile index.
    pub tile: u32,
    /// Eye rays traced.
    pub primary: u64,
    /// Secondary rays traced.
    pub secondary: u64,
    /// Seconds the worker spent rendering it.
    pub seconds: f64,
    /// Brick visits its cache served (bricked scenes; 0 otherwise).
    pub hits: u64,
    /// Bricks its cache had to load.
    pub misses: u64,
    /// Stored bytes of the bricks it loaded (from the file, or the model server).
    pub loaded: u64,
    /// Of `seconds`, those its tracers waited with every ray parked on a brick.
    pub waited: f64,
    /// Bricks its rays needed, listed after the colours.
    pub touched: u64,
}

const HEADER: usize = std::mem::size_of::<TileHeader>();

/// A rendered tile as bytes: the header, its colours (three `f32` per pixel), then the
/// bricks it needed (`u32` each; `header.touched` is set to their number).
pub fn encode_tile(header: &TileHeader, colours: &[Vec3], touched: &[u32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + colours.len() * 12 + touched.len() * 4);
    out.extend_from_slice(bytemuck::bytes_of(&TileHeader { touched: touched.len() as u64, ..*header }));
    for c in colours {
        for v in c.to_array() {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    for b in touched {
        out.extend_from_slice(&b.to_le_bytes());
    }
    out
}

/// A rendered tile's header, read before its colours (which tile it is says how many
/// colours must follow).
pub fn tile_header(bytes: &[u8]) -> Result<TileHeader> {
    match bytes.get(..HEADER) {
        Some(h) => Ok(bytemuck::pod_read_unaligned(h)),
        None => bail!("a tile message of {} bytes, shorter than its header", bytes.len()),
    }
}

/// A decoded tile: its header, colours and the bricks it needed.
pub type Tile = (TileHeader, Vec<Vec3>, Vec<u32>);

/// A rendered tile from its bytes; `pixels` is how many the tile must have.
pub fn decode_tile(bytes: &[u8], pixels: usize) -> Result<Tile> {
    let header = tile_header(bytes)?;
    let touched = usize::try_from(header.touched).ok().filter(|&t| t <= bytes.len() / 4);
    let want = touched.map(|t| HEADER + pixels * 12 + t * 4);
    let (Some(touched), Some(true)) = (touched, want.map(|w| w == bytes.len())) else {
        bail!(
            "a tile message of {} bytes, not the {pixels} pixels and {} bricks its header gives",
            bytes.len(),
            header.touched
        );
    };
    let word = |k: usize| [bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]];
    let f = |k: usize| f32::from_le_bytes(word(k));
    let colours = (0..pixels).map(|i| HEADER + 12 * i).map(|k| Vec3::new(f(k), f(k + 4), f(k + 8))).collect();
    let at = HEADER + pixels * 12;
    let bricks = (0..touched).map(|i| u32::from_le_bytes(word(at + 4 * i))).collect();
    Ok((header, colours, bricks))
}

/// Where a rank runs: its host and process id.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Whereabouts {
    /// The host's name, as MPI gives it.
    pub host: String,
    /// The process id on that host.
    pub pid: u32,
}

/// A ready message: `+host pid` when loaded, `-why` when not.
pub fn encode_ready(ready: &std::result::Result<Whereabouts, String>) -> Vec<u8> {
    match ready {
        Ok(w) => format!("+{} {}", w.host, w.pid).into_bytes(),
        Err(e) => format!("-{e}").into_bytes(),
    }
}

/// A ready message from its bytes: `Ok(Ok(where))` when the rank is ready,
/// `Ok(Err(why))` when it is not.
pub fn decode_ready(bytes: &[u8]) -> Result<std::result::Result<Whereabouts, String>> {
    let text = String::from_utf8_lossy(bytes);
    if let Some(why) = text.strip_prefix('-') {
        return Ok(Err(why.to_string()));
    }
    let ready = text.strip_prefix('+').and_then(|t| t.rsplit_once(' '));
    match ready.and_then(|(host, pid)| Some(Whereabouts { host: host.to_string(), pid: pid.parse().ok()? })) {
        Some(w) => Ok(Ok(w)),
        None => bail!("a malformed ready message of {} bytes", bytes.len()),
    }
}

/// An assignment from its bytes.
pub fn decode_assign(bytes: &[u8]) -> Result<Assign> {
    if bytes.len() != std::mem::size_of::<Assign>() {
        bail!("an assignment of {} bytes", bytes.len());
    }
    Ok(bytemuck::pod_read_unaligned(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_round_trip_bit_for_bit_and_bad_lengths_are_errors() {
        let h = TileHeader {
            frame: 3,
            tile: 7,
            primary: 1024,
            secondary: 99,
            seconds: 0.25,
            hits: 5,
            misses: 2,
            loaded: 65536,
            waited: 0.125,
            touched: 0,
        };
        let colours = vec![Vec3::new(0.1, f32::MIN_POSITIVE, -0.0), Vec3::new(1e30, 0.5, 2.0)];
        let bytes = encode_tile(&h, &colours, &[4, 9, 77]);
        let (h2, c2, t2) = decode_tile(&bytes, 2).unwrap();
        assert_eq!(h2, TileHeader { touched: 3, ..h });
        assert_eq!(t2, [4, 9, 77]);
        let bits = |v: &[Vec3]| v.iter().flat_map(|c| c.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&c2), bits(&colours));
        assert!(decode_tile(&bytes, 3).is_err());
        assert!(decode_tile(&bytes[..bytes.len() - 4], 2).is_err());
        assert!(decode_tile(&bytes[..10], 0).is_err());
        assert!(decode_assign(&[0; 7]).is_err());
    }

    #[test]
    fn ready_messages_round_trip() {
        let w = Whereabouts { host: "node 7".into(), pid: 4242 };
        assert_eq!(decode_ready(&encode_ready(&Ok(w.clone()))).unwrap(), Ok(w));
        let e = Err("missing.obj: no such file".to_string());
        assert_eq!(decode_ready(&encode_ready(&e)).unwrap(), e);
        assert!(decode_ready(b"+host").is_err() && decode_ready(b"").is_err());
    }
}

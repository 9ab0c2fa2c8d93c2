//! The codecs a bricked scene's bricks are stored with: LZ4 (the `lz4_flex` crate's
//! block format) and Zstandard (the `zstd` crate, libzstd), as Wald & Slusallek 2001
//! §6.3 store voxels LZO-compressed and unpack them on the fly. `raypipe build
//! --codec` chooses; docs/bricked-scenes.md has the measured ratios and rates.

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::bricked::Codec;

/// The zstd level bricks are written with: the fast end, as the decompression rate,
/// not the ratio, is what a demand-loading renderer waits on.
pub const ZSTD_LEVEL: i32 = 3;

/// `image` stored with `codec`.
pub fn compress(codec: Codec, image: &[u8]) -> Result<Vec<u8>> {
    match codec {
        Codec::None => Ok(image.to_vec()),
        Codec::Lz4 => Ok(lz4_flex::block::compress(image)),
        Codec::Zstd => zstd::bulk::compress(image, ZSTD_LEVEL).map_err(|e| anyhow!("zstd: {e}")),
    }
}

/// Decompresses `stored` into `out`, which has exactly the image's size; an error if
/// the stored bytes do not decompress to exactly that many.
pub fn decompress(codec: Codec, stored: &[u8], out: &mut [u8]) -> Result<()> {
    let n = match codec {
        Codec::None => {
            if stored.len() != out.len() {
                bail!("stored size {} is not the image size {}", stored.len(), out.len());
            }
            out.copy_from_slice(stored);
            stored.len()
        }
        Codec::Lz4 => lz4_flex::block::decompress_into(stored, out).map_err(|e| anyhow!("lz4: {e}"))?,
        Codec::Zstd => zstd::bulk::Decompressor::new()
            .and_then(|mut d| d.decompress_to_buffer(stored, out))
            .map_err(|e| anyhow!("zstd: {e}"))?,
    };
    if n != out.len() {
        bail!("decompressed to {n} bytes, the image has {}", out.len());
    }
    Ok(())
}

/// Parses a codec name from the command line.
pub fn parse_codec(s: &str) -> Result<Codec, String> {
    match s {
        "none" => Ok(Codec::None),
        "lz4" => Ok(Codec::Lz4),
        "zstd" => Ok(Codec::Zstd),
        _ => Err(format!("unknown codec '{s}' (lz4, zstd, none)")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_codec_round_trips_and_refuses_a_wrong_size() {
        let data: Vec<u8> = (0..10_000u32).flat_map(|i| (i % 251).to_le_bytes()).collect();
        for codec in [Codec::None, Codec::Lz4, Codec::Zstd] {
            let stored = compress(codec, &data).unwrap();
            let mut out = vec![0; data.len()];
            decompress(codec, &stored, &mut out).unwrap();
            assert_eq!(out, data, "{codec:?}");
            let mut short = vec![0; data.len() - 1];
            assert!(decompress(codec, &stored, &mut short).is_err(), "{codec:?}");
            let mut long = vec![0; data.len() + 1];
            assert!(decompress(codec, &stored, &mut long).is_err(), "{codec:?}");
        }
        assert!(decompress(Codec::Lz4, &[0xff; 16], &mut [0; 64]).is_err());
        assert!(decompress(Codec::Zstd, &[0xff; 16], &mut [0; 64]).is_err());
    }
}

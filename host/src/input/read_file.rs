//! Reading an input without being led on: only regular files are read (a device such
//! as `/dev/zero`, a FIFO or a socket — or a link to one — has no end), and never more
//! than a stated number of bytes, counted again after decompression (a gzip bomb).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use anyhow::{anyhow, bail, Result};

/// The most a text input (camera, camera path, scene file, hardware configuration,
/// sweep spec, report) may hold: far beyond any real one.
pub const TEXT_LIMIT: u64 = 256 << 20;

/// The most a mesh, scene image, glTF buffer or texture may hold, compressed or not:
/// 16 GiB, about 4× the largest scene the 32-bit image format can hold.
pub const DATA_LIMIT: u64 = 16 << 30;

/// Opens `path` for reading if it is a regular file (after following links), with its
/// length; otherwise one line naming what it is.
pub fn open_regular(path: &Path) -> Result<(File, u64)> {
    let name = path.display();
    let file = File::open(path).map_err(|e| anyhow!("{name}: cannot read: {e}"))?;
    let meta = file.metadata().map_err(|e| anyhow!("{name}: cannot read: {e}"))?;
    if !meta.is_file() {
        bail!("{name}: is {}, not a regular file", kind(&meta));
    }
    Ok((file, meta.len()))
}

/// What a non-regular file is, for messages.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() {
            return "a character device";
        } else if t.is_block_device() {
            return "a block device";
        } else if t.is_fifo() {
            return "a FIFO";
        } else if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}

/// The whole of the regular file `path`, if it holds at most `limit` bytes.
pub fn read_bytes(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let (file, len) = open_regular(path)?;
    check_len(path, len, limit)?;
    read_capped(path, file, len, limit)
}

/// The whole of the regular file `path` as UTF-8 text, if it holds at most `limit` bytes.
pub fn read_text(path: &Path, limit: u64) -> Result<String> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|_| anyhow!("{}: is not UTF-8 text", path.display()))
}

/// The regular file `path`, gzip-decompressed, if it expands to at most `limit` bytes.
pub fn read_gzip(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let (file, len) = open_regular(path)?;
    check_len(path, len, limit)?;
    let decoder = flate2::read::GzDecoder::new(std::io::BufReader::new(file));
    let mut out = Vec::new();
    decoder
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| anyhow!("{}: cannot decompress: {e}", path.display()))?;
    if out.len() as u64 > limit {
        bail!("{}: decompresses to more than {} bytes, the most an input may hold", path.display(), limit);
    }
    Ok(out)
}

fn check_len(path: &Path, len: u64, limit: u64) -> Result<()> {
    if len > limit {
        bail!("{}: {len} bytes is more than {limit}, the most this input may hold", path.display());
    }
    Ok(())
}

/// Reads `file` to its end, allocating fallibly, and stops past `limit` (a file can
/// grow while it is read).
fn read_capped(path: &Path, file: File, len: u64, limit: u64) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    out.try_reserve_exact(len as usize).map_err(|_| anyhow!("{}: {len} bytes do not fit in memory", path.display()))?;
    file.take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
    check_len(path, out.len() as u64, limit)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_fifos_are_refused_and_sizes_capped() {
        let err = read_bytes(Path::new("/dev/zero"), DATA_LIMIT).unwrap_err().to_string();
        assert_eq!(err, "/dev/zero: is a character device, not a regular file");
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("urandom.obj");
        std::os::unix::fs::symlink("/dev/urandom", &link).unwrap();
        assert!(read_text(&link, TEXT_LIMIT)
            .unwrap_err()
            .to_string()
            .ends_with("is a character device, not a regular file"));
        let big = dir.path().join("big");
        std::fs::write(&big, vec![b'a'; 100]).unwrap();
        assert!(read_bytes(&big, 99).unwrap_err().to_string().contains("100 bytes is more than 99"));
        assert_eq!(read_bytes(&big, 100).unwrap().len(), 100);
        // A gzip stream of 1 MB of zeros is a few hundred bytes.
        let gz = dir.path().join("bomb.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        std::io::Write::write_all(&mut enc, &vec![0u8; 1 << 20]).unwrap();
        std::fs::write(&gz, enc.finish().unwrap()).unwrap();
        assert!(read_gzip(&gz, 1 << 19).unwrap_err().to_string().contains("decompresses to more than"));
        assert_eq!(read_gzip(&gz, 1 << 20).unwrap().len(), 1 << 20);
    }
}

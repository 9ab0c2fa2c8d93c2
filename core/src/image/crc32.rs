//! CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), as in zlib and PNG.
//! The header's checksum covers the whole image with the checksum field read as zero,
//! so a flipped bit anywhere — including in floating-point data that no structural check
//! could catch — is reported as corruption.
//!
//! Three table sizes, one per build (the same checksum from each), chosen by feature for
//! the flash a firmware can spare:
//!
//! * default: slicing-by-8 (Kounavis & Berry 2005), eight tables of 256 entries, 8 KiB,
//!   eight bytes per step;
//! * `crc-table-1k`: the classic table of 256 entries (1 KiB), one byte per step;
//! * `crc-table-64`: 16 entries (64 bytes), four bits per step (it wins if both are set).

/// The CRC of each byte value: `BYTE[b]` (the first of the slicing tables).
#[cfg(any(test, not(feature = "crc-table-64")))]
const BYTE: [u32; 256] = make_byte_table();

/// `TABLES[k][b]` is the CRC of byte `b` followed by `k` zero bytes, so eight bytes are
/// folded in per step instead of one.
#[cfg(any(test, not(any(feature = "crc-table-1k", feature = "crc-table-64"))))]
const TABLES: [[u32; 256]; 8] = make_tables();

/// The CRC of each four-bit value.
#[cfg(any(test, feature = "crc-table-64"))]
const NIBBLE: [u32; 16] = {
    let mut t = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        t[i] = fold(i as u32, 4);
        i += 1;
    }
    t
};

/// `c` shifted through `bits` bits of the polynomial division.
const fn fold(mut c: u32, bits: u32) -> u32 {
    let mut k = 0;
    while k < bits {
        c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        k += 1;
    }
    c
}

#[cfg(any(test, not(feature = "crc-table-64")))]
const fn make_byte_table() -> [u32; 256] {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = fold(i as u32, 8);
        i += 1;
    }
    t
}

#[cfg(any(test, not(any(feature = "crc-table-1k", feature = "crc-table-64"))))]
const fn make_tables() -> [[u32; 256]; 8] {
    let mut t = [[0u32; 256]; 8];
    t[0] = make_byte_table();
    let mut k = 1;
    while k < 8 {
        let mut i = 0;
        while i < 256 {
            let prev = t[k - 1][i];
            t[k][i] = t[0][(prev & 0xFF) as usize] ^ (prev >> 8);
            i += 1;
        }
        k += 1;
    }
    t
}

/// Slicing-by-8: eight bytes per step, the rest one by one.
#[cfg(any(test, not(any(feature = "crc-table-1k", feature = "crc-table-64"))))]
fn update_sliced(mut c: u32, bytes: &[u8]) -> u32 {
    let mut chunks = bytes.chunks_exact(8);
    for b in &mut chunks {
        let lo = c ^ u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        let hi = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
        c = TABLES[7][(lo & 0xFF) as usize]
            ^ TABLES[6][((lo >> 8) & 0xFF) as usize]
            ^ TABLES[5][((lo >> 16) & 0xFF) as usize]
            ^ TABLES[4][(lo >> 24) as usize]
            ^ TABLES[3][(hi & 0xFF) as usize]
            ^ TABLES[2][((hi >> 8) & 0xFF) as usize]
            ^ TABLES[1][((hi >> 16) & 0xFF) as usize]
            ^ TABLES[0][(hi >> 24) as usize];
    }
    update_bytewise(c, chunks.remainder())
}

/// One byte per step.
#[cfg(any(test, not(feature = "crc-table-64")))]
fn update_bytewise(mut c: u32, bytes: &[u8]) -> u32 {
    for &b in bytes {
        c = BYTE[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8);
    }
    c
}

/// Four bits per step, low nibble first (the register shifts right).
#[cfg(any(test, feature = "crc-table-64"))]
fn update_nibbles(mut c: u32, bytes: &[u8]) -> u32 {
    for &b in bytes {
        c ^= b as u32;
        c = NIBBLE[(c & 0xF) as usize] ^ (c >> 4);
        c = NIBBLE[(c & 0xF) as usize] ^ (c >> 4);
    }
    c
}

/// An incremental CRC-32.
#[derive(Clone, Copy, Debug)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Crc32(0xFFFF_FFFF)
    }
}

impl Crc32 {
    /// Feeds bytes.
    pub fn update(&mut self, bytes: &[u8]) {
        #[cfg(feature = "crc-table-64")]
        let c = update_nibbles(self.0, bytes);
        #[cfg(all(feature = "crc-table-1k", not(feature = "crc-table-64")))]
        let c = update_bytewise(self.0, bytes);
        #[cfg(not(any(feature = "crc-table-1k", feature = "crc-table-64")))]
        let c = update_sliced(self.0, bytes);
        self.0 = c;
    }

    /// The checksum of everything fed so far.
    pub fn finish(self) -> u32 {
        self.0 ^ 0xFFFF_FFFF
    }
}

/// CRC-32 of one buffer.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::default();
    c.update(bytes);
    c.finish()
}

/// The CRC-32 of `bytes` with the four bytes at `at` taken as zero: how an image checks
/// itself with its checksum stored inside it (a scene image's header, a bricked scene's
/// index). Slices past the end count as empty (callers check the length first).
pub fn crc32_with_hole(bytes: &[u8], at: usize) -> u32 {
    let (head, rest) = bytes.split_at_checked(at).unwrap_or((bytes, &[]));
    let mut crc = Crc32::default();
    crc.update(head);
    crc.update(&[0; 4]);
    crc.update(rest.get(4..).unwrap_or(&[]));
    crc.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_vector() {
        // The standard check value of CRC-32/ISO-HDLC, from the build's table and from
        // each of the three.
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        for update in [update_sliced, update_bytewise, update_nibbles] {
            assert_eq!(update(0xFFFF_FFFF, b"123456789") ^ 0xFFFF_FFFF, 0xCBF4_3926);
        }
    }

    #[test]
    fn every_table_size_gives_the_bytewise_checksum() {
        // The bytewise reference, for every length and split across two updates.
        let bytewise = |data: &[u8]| update_bytewise(0xFFFF_FFFF, data) ^ 0xFFFF_FFFF;
        let data: [u8; 67] = core::array::from_fn(|i| (i as u8).wrapping_mul(37).wrapping_add(11));
        for n in 0..data.len() {
            let want = bytewise(&data[..n]);
            assert_eq!(crc32(&data[..n]), want, "length {n}");
            for update in [update_sliced, update_nibbles] {
                assert_eq!(update(0xFFFF_FFFF, &data[..n]) ^ 0xFFFF_FFFF, want, "length {n}");
            }
            let mut c = Crc32::default();
            c.update(&data[..n / 3]);
            c.update(&data[n / 3..n]);
            assert_eq!(c.finish(), want, "split {n}");
        }
    }
}

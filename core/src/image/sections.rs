//! The section table of a scene image: where each section lies, checked once for
//! alignment, bounds, record size and overlap, and typed slices of its records.

use bytemuck::Pod;

use super::error::SceneError;
use super::header::{Header, SectionEntry, SectionKind};
use super::limits::{IMAGE_ALIGN, SECTION_ALIGN};

/// The validated section table: at most one entry per kind, each inside the image.
pub(in crate::image) struct Sections<'a> {
    entries: [Option<SectionEntry>; SectionKind::ALL.len()],
    bytes: &'a [u8],
}

impl<'a> Sections<'a> {
    /// Reads and checks the table that follows the 64-byte header.
    pub(in crate::image) fn read(header: &Header, bytes: &'a [u8]) -> Result<Sections<'a>, SceneError> {
        // In u64 and then checked: `64 + 16 n` overflows a 32-bit usize for a crafted count.
        let table_end = 64 + 16 * header.section_count as u64;
        let table_end = usize::try_from(table_end).unwrap_or(usize::MAX);
        let table_bytes =
            bytes.get(64..table_end).ok_or(SceneError::Truncated { needed: table_end, len: bytes.len() })?;
        let table: &[SectionEntry] = bytemuck::try_cast_slice(table_bytes)
            .map_err(|_| SceneError::Misaligned { offset: 0, required: IMAGE_ALIGN })?;
        let mut entries = [None; SectionKind::ALL.len()];
        for e in table {
            let kind = SectionKind::from_u32(e.kind).ok_or(SceneError::UnknownSection(e.kind))?;
            let slot = &mut entries[kind as usize - 1];
            if slot.is_some() {
                return Err(SceneError::DuplicateSection(kind));
            }
            if e.offset % SECTION_ALIGN != 0 {
                return Err(SceneError::SectionMisaligned { section: kind, offset: e.offset });
            }
            let end = e.offset as u64 + e.size as u64;
            if (e.offset as usize) < table_end || end > bytes.len() as u64 {
                return Err(SceneError::SectionOutOfBounds {
                    section: kind,
                    offset: e.offset,
                    size: e.size,
                    image_size: bytes.len() as u32,
                });
            }
            if e.count as u64 * kind.record_size() as u64 != e.size as u64 {
                return Err(SceneError::SectionSize {
                    section: kind,
                    size: e.size,
                    count: e.count,
                    record_size: kind.record_size(),
                });
            }
            *slot = Some(*e);
        }
        // No two sections may share a byte.
        for (i, a) in entries.iter().enumerate() {
            for b in entries.iter().skip(i + 1) {
                if let (Some(a), Some(b)) = (a, b) {
                    let (a0, a1) = (a.offset as u64, a.offset as u64 + a.size as u64);
                    let (b0, b1) = (b.offset as u64, b.offset as u64 + b.size as u64);
                    if a.size > 0 && b.size > 0 && a0 < b1 && b0 < a1 {
                        let ka = SectionKind::from_u32(a.kind).unwrap_or(SectionKind::Positions);
                        let kb = SectionKind::from_u32(b.kind).unwrap_or(SectionKind::Positions);
                        return Err(SceneError::SectionsOverlap(ka, kb));
                    }
                }
            }
        }
        Ok(Sections { entries, bytes })
    }

    pub(in crate::image) fn entry(&self, kind: SectionKind) -> Option<SectionEntry> {
        self.entries[kind as usize - 1]
    }

    pub(in crate::image) fn count(&self, kind: SectionKind) -> u32 {
        self.entry(kind).map_or(0, |e| e.count)
    }

    pub(in crate::image) fn addr(&self, kind: SectionKind) -> u32 {
        self.entry(kind).map_or(0, |e| e.offset)
    }

    /// The records of a section, or an empty slice when it is absent.
    pub(in crate::image) fn slice<T: Pod>(&self, kind: SectionKind) -> Result<&'a [T], SceneError> {
        let Some(e) = self.entry(kind) else { return Ok(&[]) };
        let start = e.offset as usize;
        let raw = self
            .bytes
            .get(start..start + e.size as usize)
            .ok_or(SceneError::Truncated { needed: start + e.size as usize, len: self.bytes.len() })?;
        bytemuck::try_cast_slice(raw).map_err(|_| SceneError::SectionMisaligned { section: kind, offset: e.offset })
    }

    pub(in crate::image) fn required<T: Pod>(&self, kind: SectionKind) -> Result<&'a [T], SceneError> {
        if self.entry(kind).is_none() {
            return Err(SceneError::MissingSection(kind));
        }
        self.slice(kind)
    }
}

/// Whether all three coordinates are finite.
pub(in crate::image) fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

//! The check every index section shares: each value names a record that exists.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::records::NULL_INDEX;

/// Every value of `section` (in record order) is below `limit`, or is [`NULL_INDEX`] where
/// `null_allowed`; the first that is not is the error.
pub(in crate::image) fn indices_below(
    section: SectionKind,
    values: impl IntoIterator<Item = u32>,
    limit: u32,
    null_allowed: bool,
) -> Result<(), SceneError> {
    for (i, value) in values.into_iter().enumerate() {
        if value >= limit && !(null_allowed && value == NULL_INDEX) {
            return Err(SceneError::IndexOutOfRange { section, record: i as u32, value, limit });
        }
    }
    Ok(())
}

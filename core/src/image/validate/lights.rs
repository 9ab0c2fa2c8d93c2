//! LIGHTS and LIGHT_ALIAS: known kinds, finite values, area lights naming triangles and
//! kept at the tail (the point-light shaders stop before them), directions that are not
//! zero, and an alias table of probabilities with one entry per area light.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::records::{LightAlias, LightRecord};
use crate::image::sections::Sections;

/// The validated lights.
pub(in crate::image) struct Lights<'a> {
    pub lights: &'a [LightRecord],
    /// How many of `lights` (the tail) are area lights.
    pub area_lights: u32,
    pub alias: &'a [LightAlias],
}

/// The lights of an image that holds `nt` triangles.
pub(in crate::image) fn lights<'a>(s: &Sections<'a>, nt: u32) -> Result<Lights<'a>, SceneError> {
    use SectionKind as K;
    let lights: &[LightRecord] = s.slice(K::Lights)?;
    let area_lights = lights.iter().filter(|l| l.kind == LightRecord::AREA).count() as u32;
    let bad_light = |record: usize| SceneError::BadLight { section: K::Lights, record: record as u32 };
    for (i, l) in lights.iter().enumerate() {
        if l.kind > LightRecord::MAX_KIND {
            return Err(SceneError::IndexOutOfRange {
                section: K::Lights,
                record: i as u32,
                value: l.kind,
                limit: LightRecord::MAX_KIND + 1,
            });
        }
        if l.kind == LightRecord::AREA && l.triangle >= nt {
            return Err(SceneError::IndexOutOfRange {
                section: K::Lights,
                record: i as u32,
                value: l.triangle,
                limit: nt,
            });
        }
        if !(l.position.iter().chain(&l.color).all(|v| v.is_finite())) {
            return Err(SceneError::NonFinite { section: K::Lights, record: i as u32 });
        }
        if l.kind != LightRecord::AREA && i >= lights.len() - area_lights as usize {
            return Err(bad_light(i));
        }
        if l.kind == LightRecord::DIRECTIONAL && l.position == [0.0; 3] {
            return Err(bad_light(i));
        }
    }
    let alias: &[LightAlias] = s.slice(K::LightAlias)?;
    if !alias.is_empty() && alias.len() != area_lights as usize {
        return Err(SceneError::CountMismatch {
            section: K::LightAlias,
            expected: area_lights,
            found: alias.len() as u32,
        });
    }
    for (i, a) in alias.iter().enumerate() {
        let probability = |p: f32| (0.0..=1.0).contains(&p);
        if !(probability(a.keep) && probability(a.pdf) && probability(a.alias_pdf)) || a.alias >= area_lights {
            return Err(SceneError::BadLight { section: K::LightAlias, record: i as u32 });
        }
    }
    Ok(Lights { lights, area_lights, alias })
}

//! An animated transform's keyframes (`k name { transl … rot … scale … visibility … }`)
//! and the map they give at a time: `T · R · S`, scaling first, then the rotation, then
//! the translation (BART §4).

use glam::{DMat4, DQuat, DVec3};

use super::spline::{PositionSpline, RotationSpline};

/// The keyframes of one named transform.
#[derive(Clone, Debug, Default)]
pub struct Track {
    /// Translation keys.
    pub transl: Option<PositionSpline>,
    /// Rotation keys.
    pub rot: Option<RotationSpline>,
    /// Scale keys.
    pub scale: Option<PositionSpline>,
    /// `(time, visible)` switches, in time order.
    pub visibility: Vec<(f64, bool)>,
}

impl Track {
    /// The rotation at `t` (identity without rotation keys).
    pub fn rotation(&self, t: f64) -> DQuat {
        self.rot.as_ref().map_or(DQuat::IDENTITY, |r| r.at(t))
    }

    /// The map at `t`: `T · R · S`.
    pub fn matrix(&self, t: f64) -> DMat4 {
        let s = self.scale.as_ref().map_or(DVec3::ONE, |s| s.at(t));
        let p = self.transl.as_ref().map_or(DVec3::ZERO, |p| p.at(t));
        DMat4::from_scale_rotation_translation(s, self.rotation(t), p)
    }

    /// Whether the transform's objects are seen at `t`: visible until the first switch,
    /// then as the last switch at or before `t` says.
    pub fn visible(&self, t: f64) -> bool {
        self.visibility.iter().take_while(|(time, _)| *time <= t).last().is_none_or(|(_, v)| *v)
    }
}

//! BART's keyframe interpolation (Lext, Assarsson & Möller 2001, §4): positions and
//! scales on Kochanek–Bartels splines (Kochanek & Bartels 1984: Hermite segments whose
//! tangents are set by each key's tension, continuity and bias), rotations as unit
//! quaternions joined by `squad` with Kochanek–Bartels tangents taken in the
//! quaternions' logarithm space (Shoemake 1987). The first and last keys only shape the
//! end tangents: a track is defined from its second key's time to its next-to-last's,
//! and held outside. Everything is f64, as the benchmark's reference code computes it.

use glam::{DQuat, DVec3};

/// One key of a track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key<T> {
    /// Its time.
    pub t: f64,
    /// Its value.
    pub v: T,
    /// Kochanek–Bartels tension, continuity and bias.
    pub tcb: [f64; 3],
}

/// The Kochanek–Bartels weights of the outgoing tangent at key `k1` and the incoming
/// tangent at key `k2` of the segment `k1 → k2` (neighbours `k0`, `k3`): `(out0, out1)`
/// multiply `(P1 − P0, P2 − P1)`, `(in0, in1)` multiply `(P2 − P1, P3 − P2)`.
fn weights<T>(k0: &Key<T>, k1: &Key<T>, k2: &Key<T>, k3: &Key<T>) -> ([f64; 2], [f64; 2]) {
    let [t1, c1, b1] = k1.tcb;
    // Keys may share a time (BART repeats the first): a zero span gives a zero weight.
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
    let adj0 = 2.0 * ratio(k2.t - k1.t, k2.t - k0.t);
    let out0 = 0.5 * adj0 * (1.0 - t1) * (1.0 + c1) * (1.0 + b1);
    let out1 = 0.5 * adj0 * (1.0 - t1) * (1.0 - c1) * (1.0 - b1);
    let [t2, c2, b2] = k2.tcb;
    let adj1 = 2.0 * ratio(k2.t - k1.t, k3.t - k1.t);
    let in0 = 0.5 * adj1 * (1.0 - t2) * (1.0 - c2) * (1.0 + b2);
    let in1 = 0.5 * adj1 * (1.0 - t2) * (1.0 + c2) * (1.0 - b2);
    ([out0, out1], [in0, in1])
}

/// The segment index and the parameter in it for time `t` among segments spanning
/// `spans`, held at the ends.
fn locate(spans: impl ExactSizeIterator<Item = (f64, f64)>, t: f64) -> (usize, f64) {
    let n = spans.len();
    for (i, (t0, t1)) in spans.enumerate() {
        if t <= t0 {
            return (i, 0.0);
        }
        if t < t1 {
            return (i, (t - t0) / (t1 - t0));
        }
        // A zero span (keys at one time) is passed over.
    }
    (n.saturating_sub(1), 1.0)
}

/// A position (or scale) track.
#[derive(Clone, Debug)]
pub struct PositionSpline {
    // Per segment: cubic coefficients and its time interval.
    segments: Vec<([DVec3; 4], f64, f64)>,
}

impl PositionSpline {
    /// The spline through `keys` (at least four, times not decreasing: the caller
    /// checks).
    pub fn new(keys: &[Key<DVec3>]) -> PositionSpline {
        let segments = keys
            .windows(4)
            .map(|w| {
                let ([out0, out1], [in0, in1]) = weights(&w[0], &w[1], &w[2], &w[3]);
                let d = w[2].v - w[1].v;
                let t_out = out1 * d + out0 * (w[1].v - w[0].v);
                let t_in = in1 * (w[3].v - w[2].v) + in0 * d;
                let c = [w[1].v, t_out, 3.0 * d - 2.0 * t_out - t_in, -2.0 * d + t_out + t_in];
                (c, w[1].t, w[2].t)
            })
            .collect();
        PositionSpline { segments }
    }

    /// The value at time `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        let (i, u) = locate(self.segments.iter().map(|s| (s.1, s.2)), t);
        let Some(([c0, c1, c2, c3], _, _)) = self.segments.get(i) else { return DVec3::ZERO };
        *c0 + u * (*c1 + u * (*c2 + u * *c3))
    }
}

/// `ln q` of a unit quaternion: `(θ n, 0)` for `q = (sin θ n, cos θ)`.
fn log(q: DQuat) -> DVec3 {
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-12 {
        return v;
    }
    v * (s.atan2(q.w) / s)
}

/// `exp` of a pure quaternion `(v, 0)`.
fn exp(v: DVec3) -> DQuat {
    let a = v.length();
    if a < 1e-12 {
        return DQuat::from_xyzw(v.x, v.y, v.z, 1.0).normalize();
    }
    let s = a.sin() / a;
    DQuat::from_xyzw(v.x * s, v.y * s, v.z * s, a.cos())
}

/// Spherical interpolation without choosing the shorter arc (squad needs the arc it is
/// given).
fn slerp(s: f64, p: DQuat, q: DQuat) -> DQuat {
    let cos = p.dot(q).clamp(-1.0, 1.0);
    let angle = cos.acos();
    if angle.abs() < 1e-9 {
        return p;
    }
    let sin = angle.sin();
    let (a, b) = (((1.0 - s) * angle).sin() / sin, (s * angle).sin() / sin);
    DQuat::from_xyzw(a * p.x + b * q.x, a * p.y + b * q.y, a * p.z + b * q.z, a * p.w + b * q.w)
}

/// A rotation track: keys are axis–angle rotations (angle in radians).
#[derive(Clone, Debug)]
pub struct RotationSpline {
    // Per segment: p, a, b, q of squad and its time interval.
    segments: Vec<([DQuat; 4], f64, f64)>,
}

impl RotationSpline {
    /// The track through `keys` (`v` is `(axis, angle)`; at least four keys, times
    /// increasing, axes not zero: the caller checks).
    pub fn new(keys: &[Key<(DVec3, f64)>]) -> RotationSpline {
        let mut quats: Vec<DQuat> = keys.iter().map(|k| DQuat::from_axis_angle(k.v.0.normalize(), k.v.1)).collect();
        // Neighbouring keys on the same hemisphere: the path between them is the short one.
        for i in 1..quats.len() {
            if quats[i - 1].dot(quats[i]) < 0.0 {
                quats[i] = -quats[i];
            }
        }
        let segments = keys
            .windows(4)
            .zip(quats.windows(4))
            .map(|(k, q)| {
                let ([out0, out1], [in0, in1]) = weights(&k[0], &k[1], &k[2], &k[3]);
                let dq = log(q[1].inverse() * q[2]);
                let t_out = out1 * dq + out0 * log(q[0].inverse() * q[1]);
                let t_in = in1 * log(q[2].inverse() * q[3]) + in0 * dq;
                let a = q[1] * exp(0.5 * (t_out - dq));
                let b = q[2] * exp(0.5 * (dq - t_in));
                ([q[1], a, b, q[2]], k[1].t, k[2].t)
            })
            .collect();
        RotationSpline { segments }
    }

    /// The rotation at time `t`.
    pub fn at(&self, t: f64) -> DQuat {
        let (i, s) = locate(self.segments.iter().map(|s| (s.1, s.2)), t);
        let Some(([p, a, b, q], _, _)) = self.segments.get(i) else { return DQuat::IDENTITY };
        slerp(2.0 * s * (1.0 - s), slerp(s, *p, *q), slerp(s, *a, *b)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key<T>(t: f64, v: T) -> Key<T> {
        Key { t, v, tcb: [0.0; 3] }
    }

    /// A Catmull–Rom spline (zero tension, continuity, bias) passes through its inner
    /// keys, holds outside them, and is linear along evenly spaced collinear keys.
    #[test]
    fn positions_pass_through_their_keys_and_hold_outside() {
        let keys: Vec<Key<DVec3>> = (0..6).map(|i| key(i as f64, DVec3::new(2.0 * i as f64, 1.0, -3.0))).collect();
        let s = PositionSpline::new(&keys);
        for (i, k) in keys.iter().enumerate().take(5).skip(1) {
            assert!((s.at(i as f64) - k.v).length() < 1e-12, "key {i}");
        }
        assert!((s.at(2.5) - DVec3::new(5.0, 1.0, -3.0)).length() < 1e-12);
        assert_eq!(s.at(-7.0), keys[1].v);
        assert!((s.at(99.0) - keys[4].v).length() < 1e-12);
    }

    /// Rotations pass through their inner keys (up to sign), and a constant-speed turn
    /// about one axis is interpolated at constant speed.
    #[test]
    fn rotations_pass_through_their_keys_and_turn_evenly() {
        let keys: Vec<Key<(DVec3, f64)>> = (0..6).map(|i| key(i as f64, (DVec3::Y, 0.4 * i as f64))).collect();
        let s = RotationSpline::new(&keys);
        for i in 1..5 {
            let want = DQuat::from_axis_angle(DVec3::Y, 0.4 * i as f64);
            assert!(s.at(i as f64).dot(want).abs() > 1.0 - 1e-12, "key {i}");
        }
        let mid = s.at(2.5);
        let want = DQuat::from_axis_angle(DVec3::Y, 1.0);
        assert!(mid.dot(want).abs() > 1.0 - 1e-9, "{mid:?}");
    }
}

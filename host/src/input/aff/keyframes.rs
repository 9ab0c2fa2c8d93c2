//! AFF's keyframe blocks (`k name { transl … rot … scale … visibility … }`) read into
//! tracks (BART §4): at least four keys per motion, times that do not go back — or, where
//! BART's own data jump back, read as BART's reader reads them.

use anyhow::Result;
use glam::DVec3;

use super::parser::State;
use super::spline::{Key, PositionSpline, RotationSpline};
use super::tokens::Tokens;
use super::track::Track;

impl State {
    pub(super) fn keyframes(&mut self, t: &mut Tokens<'_>) -> Result<()> {
        let name = t.word("keyframes' name")?.to_string();
        let origin = format!("{}:{}", t.name, t.previous_line());
        t.open("keyframes")?;
        // A file included twice (BART's car includes each wheel file from two places)
        // gives its keyframes twice: the same block, read once.
        let again = self.track_origin.get(&name).is_some_and(|o| *o == origin);
        if self.parsed.tracks.contains_key(&name) && !again {
            return Err(t.error(format!("keyframes '{name}' are given twice (first at {})", self.track_origin[&name])));
        }
        let mut track = Track::default();
        loop {
            let kind = t.word("keyframes")?;
            if kind == "}" {
                break;
            }
            let each = match kind {
                "transl" | "scale" => 7,
                "rot" => 8,
                "visibility" => 2,
                other => return Err(t.error(format!("keyframes '{name}': unknown motion '{other}'"))),
            };
            let n = t.count("a keyframe count", each)?;
            let least = if kind == "visibility" { 1 } else { 4 };
            if n < least {
                return Err(t.error(format!("keyframes '{name}': {kind} needs at least {least} keys, has {n}")));
            }
            let mut times = Vec::with_capacity(n);
            let mut rows = Vec::with_capacity(n);
            let mut jumped = false;
            for _ in 0..n {
                let time = t.number("a key time")?;
                // BART repeats the first key's time (the first key only shapes a tangent),
                // and four of its robots' tracks jump back in time. The benchmark's reader
                // takes the first segment that ends after `t`, which reaches the keys
                // after a jump only once `t` passes the keys before it; [`locate`] does
                // the same, so they are read as they are, with a warning.
                if let Some(&last) = times.last() {
                    if time < last && !jumped {
                        jumped = true;
                        self.parsed.warnings.push(format!(
                            "{}:{}: keyframes '{name}': {kind} times go back from {last} to {time}; the keys from there on apply only after {last}, as in BART's reader",
                            t.name,
                            t.previous_line()
                        ));
                    }
                }
                times.push(time);
                let row: Vec<f64> = (1..each).map(|_| t.number("a key value")).collect::<Result<_>>()?;
                rows.push(row);
            }
            let tcb = |r: &[f64]| [r[r.len() - 3], r[r.len() - 2], r[r.len() - 1]];
            let clash = |t: &Tokens<'_>| t.error(format!("keyframes '{name}': {kind} is given twice"));
            match kind {
                "transl" | "scale" => {
                    let keys: Vec<Key<DVec3>> = times
                        .iter()
                        .zip(&rows)
                        .map(|(&time, r)| Key { t: time, v: DVec3::new(r[0], r[1], r[2]), tcb: tcb(r) })
                        .collect();
                    let slot = if kind == "transl" { &mut track.transl } else { &mut track.scale };
                    if slot.replace(PositionSpline::new(&keys)).is_some() {
                        return Err(clash(t));
                    }
                }
                "rot" => {
                    if rows.iter().any(|r| DVec3::new(r[0], r[1], r[2]).length_squared() == 0.0) {
                        return Err(t.error(format!("keyframes '{name}': a rotation about a zero axis")));
                    }
                    let keys: Vec<Key<(DVec3, f64)>> = times
                        .iter()
                        .zip(&rows)
                        .map(|(&time, r)| Key {
                            t: time,
                            v: (DVec3::new(r[0], r[1], r[2]), r[3].to_radians()),
                            tcb: tcb(r),
                        })
                        .collect();
                    if track.rot.replace(RotationSpline::new(&keys)).is_some() {
                        return Err(clash(t));
                    }
                }
                _ => {
                    if !track.visibility.is_empty() {
                        return Err(clash(t));
                    }
                    track.visibility = times.iter().zip(&rows).map(|(&time, r)| (time, r[0] != 0.0)).collect();
                }
            }
        }
        self.track_origin.insert(name.clone(), origin);
        self.parsed.tracks.insert(name, track);
        Ok(())
    }
}

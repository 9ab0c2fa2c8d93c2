//! The oracle of the multipass loop (Purcell 2002 §3.2, §4.2): after each pass it picks
//! the kind of the next one from how many rays wait for each kernel (what an occlusion
//! query would count).
//!
//! - **Delany**: an intersection pass once at least a fraction (20%) of the active rays
//!   wait to intersect, else a traversal pass.
//! - **Naive**: traversal and intersection passes alternate, whoever waits.
//! - **Optimal**: clairvoyant. It knows every ray's remaining kernel sequence and picks
//!   the kind that leaves the smaller lower bound on the passes still to come (the
//!   largest remaining traversal passes of any ray plus the largest remaining
//!   intersection passes of any ray; ties: the kind more rays wait for). The bound it
//!   chases is Purcell's optimum, max traversal steps + max intersections; it meets it
//!   whenever the ray that needs the most traversal passes is not held up by
//!   intersections that the ray needing the most intersections does not share (always
//!   for one ray, or rays with the same sequence), and no schedule can do better than
//!   it in general.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

/// The kind of a loop pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum LoopPass {
    /// Every ray waiting to traverse takes up to N steps.
    Traverse,
    /// Every ray waiting to intersect tests up to M triangles.
    Intersect,
}

/// How the next pass is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Oracle {
    /// Delany's rule with its fraction (Purcell: 0.2).
    Delany(f64),
    /// Strict alternation, starting with traversal.
    Naive,
    /// Clairvoyant: minimises the remaining lower bound.
    Optimal,
}

impl Default for Oracle {
    fn default() -> Self {
        Oracle::Delany(DELANY_FRACTION)
    }
}

/// Delany's threshold as Purcell used it (§4.2: "at least 20%").
pub const DELANY_FRACTION: f64 = 0.2;

/// What the oracle may look at before a pass.
#[derive(Clone, Copy, Debug, Default)]
pub struct Waiting {
    /// Rays waiting for a traversal step.
    pub traverse: u64,
    /// Rays waiting to intersect.
    pub intersect: u64,
    /// The lower bound left after a traversal pass / after an intersection pass
    /// (only the optimal oracle computes these).
    pub bound_after: Option<(u64, u64)>,
}

impl Oracle {
    /// The next pass; `last` is the previous loop pass, if any. Never a pass kind that
    /// no ray waits for, except under the naive rule's strict alternation.
    pub fn next(&self, w: &Waiting, last: Option<LoopPass>) -> LoopPass {
        match *self {
            Oracle::Naive => match last {
                Some(LoopPass::Traverse) => LoopPass::Intersect,
                _ => LoopPass::Traverse,
            },
            Oracle::Delany(f) => {
                let active = w.traverse + w.intersect;
                if w.intersect > 0 && (w.traverse == 0 || w.intersect as f64 >= f * active as f64) {
                    LoopPass::Intersect
                } else {
                    LoopPass::Traverse
                }
            }
            Oracle::Optimal => {
                if w.intersect == 0 {
                    return LoopPass::Traverse;
                }
                if w.traverse == 0 {
                    return LoopPass::Intersect;
                }
                match w.bound_after {
                    Some((after_t, after_i)) if after_t != after_i => {
                        if after_t < after_i {
                            LoopPass::Traverse
                        } else {
                            LoopPass::Intersect
                        }
                    }
                    _ if w.intersect > w.traverse => LoopPass::Intersect,
                    _ => LoopPass::Traverse,
                }
            }
        }
    }

    /// True for the clairvoyant oracle (the loop then keeps every ray's future).
    pub fn needs_future(&self) -> bool {
        matches!(self, Oracle::Optimal)
    }
}

impl fmt::Display for Oracle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Oracle::Delany(x) => write!(f, "delany:{x}"),
            Oracle::Naive => write!(f, "naive"),
            Oracle::Optimal => write!(f, "optimal"),
        }
    }
}

impl FromStr for Oracle {
    type Err = String;

    fn from_str(s: &str) -> Result<Oracle, String> {
        let (name, arg) = match s.split_once(':') {
            Some((n, a)) => (n, Some(a)),
            None => (s, None),
        };
        match (name, arg) {
            ("delany", None) => Ok(Oracle::Delany(DELANY_FRACTION)),
            ("delany", Some(a)) => {
                let f: f64 = a.parse().map_err(|_| format!("oracle {s:?}: '{a}' is not a fraction"))?;
                if !(f > 0.0 && f <= 1.0) {
                    return Err(format!("oracle {s:?}: the fraction must be in (0, 1]"));
                }
                Ok(Oracle::Delany(f))
            }
            ("naive", None) => Ok(Oracle::Naive),
            ("optimal", None) => Ok(Oracle::Optimal),
            _ => Err(format!("oracle {s:?}: expected delany[:FRACTION], naive or optimal")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delany_intersects_at_the_fraction() {
        let o = Oracle::Delany(0.2);
        let w = |t, i| Waiting { traverse: t, intersect: i, bound_after: None };
        assert_eq!(o.next(&w(80, 20), None), LoopPass::Intersect);
        assert_eq!(o.next(&w(81, 19), None), LoopPass::Traverse);
        assert_eq!(o.next(&w(0, 1), None), LoopPass::Intersect);
        assert_eq!(o.next(&w(5, 0), None), LoopPass::Traverse);
    }

    #[test]
    fn naive_alternates_and_parsing_rejects_nonsense() {
        let w = Waiting { traverse: 0, intersect: 3, bound_after: None };
        assert_eq!(Oracle::Naive.next(&w, None), LoopPass::Traverse);
        assert_eq!(Oracle::Naive.next(&w, Some(LoopPass::Traverse)), LoopPass::Intersect);
        assert_eq!("delany:0.5".parse::<Oracle>(), Ok(Oracle::Delany(0.5)));
        for bad in ["delany:0", "delany:1.5", "delany:x", "naive:2", "best"] {
            assert!(bad.parse::<Oracle>().is_err(), "{bad}");
        }
    }
}

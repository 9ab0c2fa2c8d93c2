//! The arithmetic of the traversal and intersection datapaths: `f32` (the default), or a
//! fixed-point format of raypipe-core's fixed-point datapath — its box test in the
//! traversal units and its watertight triangle test in the intersection units
//! (`raypipe_core::traverse::boxes::fixed_slab`, `raypipe_core::intersect::fixed_watertight`).
//! The choice changes what the units compute, not how long they take: the latencies are
//! the configuration's own (`traversal.step_latency`, `intersection.latency`).

use serde::{Deserialize, Serialize};

use raypipe_core::math::fixed_point::QFormat;

/// The datapath's number format. The fixed-point ones are those raypipe-core is built
/// for here (its format is a type parameter): 32-bit and 24-bit registers with the
/// point in a few places.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Datapath {
    /// IEEE single precision (the watertight test, or the one `--intersector` names).
    #[default]
    #[serde(rename = "f32")]
    F32,
    /// 32 bits, 16 of them fraction.
    #[serde(rename = "q16.16")]
    Q16_16,
    /// 32 bits, 12 fraction.
    #[serde(rename = "q20.12")]
    Q20_12,
    /// 32 bits, 20 fraction.
    #[serde(rename = "q12.20")]
    Q12_20,
    /// 32 bits, 8 fraction.
    #[serde(rename = "q24.8")]
    Q24_8,
    /// 24 bits, 12 fraction.
    #[serde(rename = "q12.12")]
    Q12_12,
    /// 24 bits, 16 fraction.
    #[serde(rename = "q8.16")]
    Q8_16,
    /// 24 bits, 8 fraction.
    #[serde(rename = "q16.8")]
    Q16_8,
}

impl Datapath {
    /// Every choice.
    pub const ALL: [Datapath; 8] = [
        Datapath::F32,
        Datapath::Q16_16,
        Datapath::Q20_12,
        Datapath::Q12_20,
        Datapath::Q24_8,
        Datapath::Q12_12,
        Datapath::Q8_16,
        Datapath::Q16_8,
    ];

    /// The fixed-point format, or `None` for `f32`.
    pub fn format(self) -> Option<QFormat> {
        let q = |bits, frac| Some(QFormat { bits, frac });
        match self {
            Datapath::F32 => None,
            Datapath::Q16_16 => q(32, 16),
            Datapath::Q20_12 => q(32, 12),
            Datapath::Q12_20 => q(32, 20),
            Datapath::Q24_8 => q(32, 8),
            Datapath::Q12_12 => q(24, 12),
            Datapath::Q8_16 => q(24, 16),
            Datapath::Q16_8 => q(24, 8),
        }
    }

    /// The name in configurations and on the command line ("f32", "q16.16", …).
    pub fn name(self) -> String {
        match self.format() {
            None => "f32".into(),
            Some(f) => format!("q{}.{}", f.bits - f.frac, f.frac),
        }
    }
}

impl core::str::FromStr for Datapath {
    type Err = String;

    fn from_str(s: &str) -> Result<Datapath, String> {
        let want = s.trim().to_ascii_lowercase();
        Datapath::ALL.into_iter().find(|d| d.name() == want).ok_or_else(|| {
            let names: Vec<String> = Datapath::ALL.iter().map(|d| d.name()).collect();
            format!("unknown datapath {s:?} (choose from {})", names.join(", "))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_formats_are_supported() {
        for d in Datapath::ALL {
            assert_eq!(d.name().parse::<Datapath>(), Ok(d));
            assert!(d.format().is_none_or(|f| f.is_supported()));
            let toml = toml::to_string(&std::collections::BTreeMap::from([("d", d)])).unwrap();
            assert!(toml.contains(&format!("\"{}\"", d.name())), "{toml}");
        }
        assert!("q3.3".parse::<Datapath>().unwrap_err().contains("q16.16"));
    }
}

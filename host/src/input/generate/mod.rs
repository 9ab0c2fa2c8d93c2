//! Procedural scenes that raypipe generates itself: stand-ins for the two
//! million-triangle scenes of Purcell 2002 (Soda Hall, a building interior of rooms and
//! furniture; a forest of trees), each with the paper's two views. `NAME[:key=value,...]`
//! picks a generator and its parameters; the same parameters give the same scene.

pub mod building;
pub mod forest;
pub mod museum_art;
pub mod power_plant;
pub mod shapes;

use anyhow::{bail, Result};

use crate::input::camera_file::CameraSpec;
use crate::input::limits;
use crate::input::mesh::Mesh;

/// A generated scene: its mesh and the camera of the chosen view.
pub struct Generated {
    /// A name for reports ("building:floors=6,...").
    pub name: String,
    /// The triangles, materials and lights.
    pub mesh: Mesh,
    /// The view's camera.
    pub camera: CameraSpec,
}

/// Parameters as `key=value` pairs, each read once.
struct Params<'a> {
    spec: &'a str,
    pairs: Vec<(&'a str, &'a str, bool)>,
}

impl<'a> Params<'a> {
    fn parse(spec: &'a str, text: &'a str) -> Result<Params<'a>> {
        let mut pairs = Vec::new();
        for p in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let Some((k, v)) = p.split_once('=') else { bail!("--generate {spec}: expected key=value, got '{p}'") };
            pairs.push((k.trim(), v.trim(), false));
        }
        Ok(Params { spec, pairs })
    }

    /// A whole number in `lo..=hi`.
    fn get(&mut self, key: &str, default: u32, lo: u32, hi: u32) -> Result<u32> {
        let Some(p) = self.pairs.iter_mut().find(|p| p.0 == key) else { return Ok(default) };
        p.2 = true;
        let v: u32 =
            p.1.parse()
                .map_err(|_| anyhow::anyhow!("--generate {}: {key}={} is not a whole number", self.spec, p.1))?;
        if !(lo..=hi).contains(&v) {
            bail!("--generate {}: {key}={v} is not between {lo} and {hi}", self.spec);
        }
        Ok(v)
    }

    /// Fails on a key no generator parameter read.
    fn finish(self, known: &[&str]) -> Result<()> {
        if let Some(p) = self.pairs.iter().find(|p| !p.2) {
            bail!("--generate {}: unknown parameter '{}' (parameters: {})", self.spec, p.0, known.join(", "));
        }
        Ok(())
    }
}

/// Generates `spec` (`building[:floors=F,rooms=R,seed=S]` or
/// `forest[:trees=T,leaves=L,seed=S]`) seen from `view` (building: outside, inside;
/// forest: top, inside; default: the first).
pub fn generate(spec: &str, view: Option<&str>) -> Result<Generated> {
    let (name, params) = spec.split_once(':').unwrap_or((spec, ""));
    let mut p = Params::parse(spec, params)?;
    let (mesh, views): (Mesh, Vec<(&str, CameraSpec)>) = match name {
        "building" => {
            let b = building::Building {
                floors: p.get("floors", 6, 1, 64)?,
                rooms: p.get("rooms", 12, 1, 64)?,
                seed: p.get("seed", 1, 0, u32::MAX)?,
            };
            p.finish(&["floors", "rooms", "seed"])?;
            limits::check_triangles(&format!("--generate {spec}"), b.triangle_bound())?;
            (b.mesh(), b.views())
        }
        "forest" => {
            let f = forest::Forest {
                trees: p.get("trees", 1200, 1, 100_000)?,
                leaves: p.get("leaves", 800, 0, 10_000)?,
                seed: p.get("seed", 1, 0, u32::MAX)?,
            };
            p.finish(&["trees", "leaves", "seed"])?;
            // Counted before a single leaf is made: 10⁵ trees of 10⁴ leaves is 10⁹.
            limits::check_triangles(&format!("--generate {spec}"), f.triangle_count())?;
            (f.mesh(), f.views())
        }
        "powerplant" => {
            let pp = power_plant_params(&mut p)?;
            p.finish(&["triangles", "seed"])?;
            limits::check_triangles(&format!("--generate {spec}"), pp.triangles)?;
            let mut mesh = Mesh { materials: power_plant::PowerPlant::materials(), ..Default::default() };
            pp.stream(&mut |t, m| {
                let base = mesh.positions.len() as u32;
                mesh.positions.extend(t.map(|v| v.to_array()));
                mesh.triangles.push([base, base + 1, base + 2]);
                mesh.tri_materials.push(m);
                Ok(())
            })?;
            mesh.material_names = (0..mesh.materials.len()).map(|k| format!("m{k}")).collect();
            (mesh, power_plant::PowerPlant::views())
        }
        _ => bail!("--generate {spec}: unknown scene '{name}' (building, forest, powerplant)"),
    };
    let names: Vec<&str> = views.iter().map(|v| v.0).collect();
    let camera = match view {
        None => views[0].1,
        Some(v) => match views.iter().find(|(n, _)| *n == v) {
            Some((_, c)) => *c,
            None => bail!("--view {v}: {name} has the views {}", names.join(", ")),
        },
    };
    limits::check_triangles(&format!("--generate {spec}"), mesh.triangles.len() as u64)?;
    Ok(Generated { name: spec.to_string(), mesh, camera })
}

/// The power plant's parameters from `spec`.
fn power_plant_params(p: &mut Params<'_>) -> Result<power_plant::PowerPlant> {
    let pp = power_plant::PowerPlant {
        triangles: p.get("triangles", 12_500_000, 1_000, u32::MAX - 1)? as u64,
        seed: p.get("seed", 1, 0, u32::MAX)?,
    };
    Ok(pp)
}

/// A generated scene streamed rather than held: the power plant (`powerplant[:triangles=N,
/// seed=S]`), for bricked builds of any size. `None` for the other generators.
pub fn generate_stream(spec: &str, view: Option<&str>) -> Result<Option<(power_plant::PowerPlant, CameraSpec)>> {
    let (name, params) = spec.split_once(':').unwrap_or((spec, ""));
    if name != "powerplant" {
        return Ok(None);
    }
    let mut p = Params::parse(spec, params)?;
    let pp = power_plant_params(&mut p)?;
    p.finish(&["triangles", "seed"])?;
    let views = power_plant::PowerPlant::views();
    let camera = match view {
        None => views[0].1,
        Some(v) => match views.iter().find(|(n, _)| *n == v) {
            Some((_, c)) => *c,
            None => bail!("--view {v}: powerplant has the views outside, inside"),
        },
    };
    Ok(Some((pp, camera)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_counts_are_known_before_generating() {
        for (trees, leaves) in [(1, 0), (3, 10), (40, 7)] {
            let f = forest::Forest { trees, leaves, seed: 3 };
            assert_eq!(f.triangle_count(), f.mesh().triangles.len() as u64);
        }
        for (floors, rooms, seed) in [(1, 1, 0), (2, 3, 9), (3, 2, 77)] {
            let b = building::Building { floors, rooms, seed };
            let made = b.mesh().triangles.len() as u64;
            assert!(made <= b.triangle_bound() && made * 10 > b.triangle_bound() * 7, "{made} {}", b.triangle_bound());
        }
        // Both within their parameter ranges, together 10⁹ triangles: refused at once.
        let e = generate("forest:trees=100000,leaves=10000", None).err().unwrap().to_string();
        assert!(e.contains("1001608192 triangles is more than 33554432"), "{e}");
        let e = generate("building:floors=64,rooms=64", None).err().unwrap().to_string();
        assert!(e.contains("is more than 33554432"), "{e}");
    }
}

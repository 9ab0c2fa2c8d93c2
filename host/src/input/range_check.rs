//! Flags scenes and rays outside raypipe-core's guaranteed range (`raypipe_core::range`):
//! there every structure, packet size and driver still runs, but may return a different
//! hit. One warning line per input, with the count, the first offender and the reason.

use raypipe_core::range::{check_ray, check_scene};
use raypipe_core::{Ray, SceneView};

/// The warnings for `view`'s scene and for `rays` (named `what` in the message).
pub fn warnings(view: &SceneView<'_>, rays: &[Ray], what: &str) -> Vec<String> {
    let mut out = Vec::new();
    if let Err(e) = check_scene(view) {
        let (lo, hi) = view.bounds();
        out.push(format!(
            "the scene is outside the guaranteed range ({e}: extent {}); hits may differ between structures",
            (hi - lo).max_element()
        ));
    }
    let mut outside = rays.iter().enumerate().filter_map(|(i, r)| check_ray(view, r).err().map(|e| (i, e)));
    if let Some((first, e)) = outside.next() {
        let n = 1 + outside.count();
        out.push(format!(
            "{what}: {n} of {} lie outside the guaranteed range (the first, number {first}: {e}); their hits may differ between structures",
            rays.len()
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{self, Accel, BuildOptions};
    use raypipe_core::Vec3;

    #[test]
    fn far_rays_are_counted_and_the_first_named() {
        let mesh = crate::input::mesh::Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            ..Default::default()
        };
        let opts = BuildOptions { accel: Accel::Bvh, ..Default::default() };
        let s = scene::build("t".into(), mesh, Vec::new(), Default::default(), &opts).unwrap();
        let view = s.view().unwrap();
        let near = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        let far = Ray::new(Vec3::new(0.2, 0.2, 100.0), -Vec3::Z);
        assert!(warnings(&view, &[near, near], "rays").is_empty());
        let w = warnings(&view, &[near, far, near, far], "rays");
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("rays: 2 of 4 lie outside the guaranteed range (the first, number 1: the ray starts"),
            "{w:?}"
        );
    }
}

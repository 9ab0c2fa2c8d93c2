//! `raypipe render`: the default scene, thread counts, inputs, algorithms, lights,
//! textures and HDR outputs.

use crate::common::*;

#[test]
fn render_without_arguments_draws_the_cornell_box() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["render"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h, px) = decode(&dir.path().join("raypipe.png"));
    assert_eq!((w, h), (512, 512));
    // Red wall on the left, green wall on the right, at mid height.
    let at = |x: usize, y: usize| &px[(y * w as usize + x) * 3..(y * w as usize + x) * 3 + 3];
    let left = at(30, 256);
    let right = at(480, 256);
    assert!(left[0] > 2 * left[1] && left[0] > 100, "left wall {left:?}");
    assert!(right[1] > right[0] && right[1] > right[2], "right wall {right:?}");
    // The ceiling light is emissive: bright.
    assert!(at(256, 72).iter().all(|&c| c > 200), "light {:?}", at(256, 72));
}

#[test]
fn image_is_identical_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    for t in ["1", "2", "3"] {
        let name = format!("t{t}.png");
        let o = raypipe(dir.path(), &["render", "-o", &name, "--size", "97x61", "--threads", t]);
        assert!(o.status.success());
        images.push(std::fs::read(dir.path().join(name)).unwrap());
    }
    assert!(images.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn gzipped_obj_renders_like_the_plain_file() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = std::fs::read(fixtures().join("tetra.obj")).unwrap();
    std::fs::copy(fixtures().join("tetra.mtl"), d.join("tetra.mtl")).unwrap();
    std::fs::write(d.join("tetra.obj"), &text).unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(&text).unwrap();
    std::fs::write(d.join("packed.obj.gz"), gz.finish().unwrap()).unwrap();
    let a = raypipe(d, &["render", "tetra.obj", "-o", "a.png", "--size", "40x30"]);
    let b = raypipe(d, &["render", "packed.obj.gz", "-o", "b.png", "--size", "40x30"]);
    assert!(a.status.success() && b.status.success(), "{} {}", stderr(&a), stderr(&b));
    assert_eq!(decode(&d.join("a.png")), decode(&d.join("b.png")));
    std::fs::write(d.join("broken.obj.gz"), b"\x1f\x8b\x08\x00garbage").unwrap();
    assert_one_line_error(&raypipe(d, &["build", "broken.obj.gz", "-o", "x.rpsi"]), "broken.obj.gz");
}

#[test]
fn algorithms_render_simulate_and_report_their_costs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = fixtures().join("whitted.obj");
    let scene = scene.to_str().unwrap();
    for algo in ["cast", "shadow", "whitted", "path"] {
        let common = ["--algo", algo, "--size", "48x36", "--samples", "2"];
        let mut render = vec!["render", scene, "-o", "r.png"];
        render.extend_from_slice(&common);
        let o = raypipe(dir.path(), &render);
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        let mut sim = vec!["simulate", scene, "-o", "s.png", "--report", "s.json", "--preset", "saarcor"];
        sim.extend_from_slice(&common);
        let o = raypipe(dir.path(), &sim);
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        assert_eq!(decode(&dir.path().join("r.png")), decode(&dir.path().join("s.png")), "{algo}: model = host");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
        assert!(json["rays_by_kind"]["shadow"].as_u64().unwrap() > 0 || algo == "cast", "{algo}");
        let mut stats = vec!["stats", scene];
        stats.extend_from_slice(&common);
        let o = raypipe(dir.path(), &stats);
        assert!(o.status.success(), "{algo}: {}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        if algo != "cast" {
            assert!(out.contains("rays per pixel") && out.contains("relative to ray casting"), "{algo}: {out}");
        }
        if algo == "shadow" {
            assert!(out.contains("rasterization and ray casting disagree at"), "{out}");
        }
    }
    for (args, needle) in [
        (vec!["render", "--algo", "path", "--samples", "0"], "--samples"),
        (vec!["render", "--algo", "whitted", "--max-depth", "100"], "--max-depth"),
        (vec!["simulate", "--algo", "path", "--bounces", "99"], "--bounces"),
    ] {
        assert_one_line_error(&raypipe(dir.path(), &args), needle);
    }
}

#[test]
fn point_lights_from_the_command_line_and_enclosed_lights_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let scene = fixtures().join("whitted.obj");
    let scene = scene.to_str().unwrap();
    let o = raypipe(dir.path(), &["render", scene, "--algo", "whitted", "--size", "40x30", "-o", "a.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raypipe(
        dir.path(),
        &["render", scene, "--algo", "whitted", "--size", "40x30", "-o", "b.png", "--light=-1.5,2.5,1.5,0.5,0.5,0.6"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(decode(&dir.path().join("a.png")), decode(&dir.path().join("b.png")), "the light moved");
    // A light inside a closed cube lights nothing outside it: a warning, not an error.
    let mut obj = String::new();
    for v in ["-1 -1 -1", "1 -1 -1", "1 1 -1", "-1 1 -1", "-1 -1 1", "1 -1 1", "1 1 1", "-1 1 1"] {
        obj += &format!("v {v}\n");
    }
    for f in
        ["1 3 2", "1 4 3", "5 6 7", "5 7 8", "1 2 6", "1 6 5", "4 8 7", "4 7 3", "1 5 8", "1 8 4", "2 3 7", "2 7 6"]
    {
        obj += &format!("f {f}\n");
    }
    let cube = write(dir.path(), "cube.obj", &obj);
    let o = raypipe(dir.path(), &["render", cube.to_str().unwrap(), "--light", "0,0,0", "-o", "c.png"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("inside closed geometry"), "{}", stderr(&o));
    let o = raypipe(dir.path(), &["render", cube.to_str().unwrap(), "--light", "0,3,0", "-o", "c.png"]);
    assert!(!stderr(&o).contains("inside closed geometry"), "{}", stderr(&o));
    let o = raypipe(dir.path(), &["render", "--light", "0,nan,0", "-o", "c.png"]);
    assert!(!o.status.success());
}

/// A quad whose diffuse texture is a 2×2 checker (PNG): each quarter of the picture
/// takes its texel's colour; a missing texture or an unsupported format is one warning
/// and the material's own colour.
#[test]
fn diffuse_textures_are_sampled_and_bad_ones_fall_back_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let texels: [[u8; 3]; 4] = [[230, 20, 20], [20, 230, 20], [20, 20, 230], [230, 230, 230]];
    let file = std::fs::File::create(dir.path().join("checker.png")).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 2, 2);
    enc.set_color(png::ColorType::Rgb);
    enc.write_header().unwrap().write_image_data(texels.as_flattened()).unwrap();
    let obj = "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\nf 1/1 2/2 3/3 4/4\n";
    write(dir.path(), "quad.obj", obj);
    let camera = "eye 0 0 2.2\nlook_at 0 0 0\nup 0 1 0\nfov 60\nsize 40 40\nbackground 0 0 0\n";
    write(dir.path(), "quad.camera", camera);
    let render = |mtl: &str| {
        write(dir.path(), "quad.mtl", mtl);
        let o = raypipe(dir.path(), &["render", "quad.obj", "--light", "0,0,3", "-o", "q.png"]);
        assert!(o.status.success(), "{}", stderr(&o));
        (decode(&dir.path().join("q.png")).2, stderr(&o))
    };
    let (px, err) = render("newmtl tex\nKd 1 1 1\nmap_Kd -clamp on checker.png\n");
    assert!(!err.contains("warning"), "{err}");
    let at = |x: usize, y: usize| &px[(y * 40 + x) * 3..(y * 40 + x) * 3 + 3];
    // Top-left quarter: the texture's top-left texel (red); bottom-right: white.
    let (tl, tr, bl, br) = (at(12, 12), at(27, 12), at(12, 27), at(27, 27));
    assert!(tl[0] > 2 * tl[1] && tl[0] > 2 * tl[2], "top left {tl:?}");
    assert!(tr[1] > 2 * tr[0] && tr[1] > 2 * tr[2], "top right {tr:?}");
    assert!(bl[2] > 2 * bl[0] && bl[2] > 2 * bl[1], "bottom left {bl:?}");
    assert!(br[0] > 100 && br[1] > 100 && br[2] > 100, "bottom right {br:?}");
    for (mtl, needle) in [
        ("newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd missing.png\n", "missing.png"),
        ("newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd checker.bmp\n", "unsupported image format"),
    ] {
        if needle.contains("unsupported") {
            std::fs::copy(dir.path().join("checker.png"), dir.path().join("checker.bmp")).unwrap();
        }
        let (px, err) = render(mtl);
        assert!(err.contains("warning") && err.contains(needle), "{err}");
        let c = &px[(20 * 40 + 20) * 3..(20 * 40 + 20) * 3 + 3];
        assert!(c[0] == c[1] && c[1] == c[2] && c[0] > 0, "grey diffuse colour: {c:?}");
    }
}

/// HDR outputs: `.exr` and `.pfm` hold the linear framebuffer exactly;
/// exposure and tone mapping change only the PNG; outputs get the umask's permissions.
#[test]
fn hdr_outputs_hold_the_linear_framebuffer() {
    use raypipe::render::{render, Algorithm, RenderOptions};
    let dir = tempfile::tempdir().unwrap();
    let args = ["--algo", "whitted", "--size", "48x40", "--samples", "4", "--filter", "tent"];
    for out in ["a.exr", "a.pfm", "a.png", "b.png"] {
        let mut all = vec!["render", "-o", out];
        all.extend(args);
        if out == "b.png" {
            all.extend(["--exposure", "1.5", "--tonemap", "aces"]);
        }
        let o = raypipe(dir.path(), &all);
        assert!(o.status.success(), "{out}: {}", stderr(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("4 samples per pixel") && stdout.contains("Mrays/s"), "{stdout}");
        assert!(stdout.contains("load") && stdout.contains("build") && stdout.contains("render"), "{stdout}");
    }
    // The same frame in-process.
    let scene = raypipe::scene::load(None, &Default::default()).unwrap();
    let view = scene.view().unwrap();
    let cam = raypipe_core::image::CameraRecord { width: 48, height: 40, ..*view.camera().unwrap() };
    let opts = RenderOptions {
        algo: Algorithm::Whitted,
        samples: 4,
        filter: raypipe_core::pixel_filter::Filter::Tent,
        packet: raypipe::render::packets::PacketSize::auto_for(&view),
        ..Default::default()
    };
    let frame = render(&view, &cam, &opts).unwrap();

    let mut exr = vec![[f32::NAN; 3]; 48 * 40];
    let image = exr::prelude::read_first_rgba_layer_from_file(
        dir.path().join("a.exr"),
        |res, _| {
            assert_eq!((res.width(), res.height()), (48, 40));
            vec![[0.0f32; 3]; 48 * 40]
        },
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * 48 + pos.x()] = [r, g, b],
    )
    .unwrap();
    exr.copy_from_slice(&image.layer_data.channel_data.pixels);
    assert!(exr == frame.radiance, "EXR values equal the linear framebuffer");
    assert!(frame.radiance.iter().any(|c| c.iter().any(|&v| v > 0.0 && v != 1.0)));

    let pfm = std::fs::read(dir.path().join("a.pfm")).unwrap();
    let header = b"PF\n48 40\n-1.0\n";
    assert_eq!(&pfm[..header.len()], header);
    let floats: Vec<f32> =
        pfm[header.len()..].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    for y in 0..40 {
        for x in 0..48 {
            // Rows bottom to top.
            let at = ((39 - y) * 48 + x) * 3;
            assert_eq!(&floats[at..at + 3], &frame.radiance[y * 48 + x], "pfm pixel {x},{y}");
        }
    }
    let (_, _, plain) = decode(&dir.path().join("a.png"));
    assert_eq!(plain, frame.pixels.as_flattened(), "the default PNG is the clamped sRGB image");
    let (_, _, mapped) = decode(&dir.path().join("b.png"));
    assert_ne!(plain, mapped, "exposure and tone mapping change the PNG");

    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(dir.path().join("a.png")).unwrap().permissions().mode() & 0o777;
        // SAFETY: umask has no memory-safety preconditions; it is put straight back.
        let mask = unsafe {
            let m = libc::umask(0o022);
            libc::umask(m);
            m
        } as u32;
        assert_eq!(mode, 0o666 & !mask, "output permissions follow the umask");
    }
    for (bad, what) in [("x.jpg", "must be a .png, .exr or .pfm"), ("nodir/x.exr", "does not exist")] {
        let o = raypipe(dir.path(), &["render", "-o", bad, "--size", "8x8"]);
        assert_one_line_error(&o, what);
    }
    let o = raypipe(dir.path(), &["render", "-o", "c.png", "--exposure", "inf"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "a usage error: {err}");
    assert!(err.trim().lines().count() == 1 && err.contains("--exposure"), "{err}");
    // Path tracing exposes automatically and says so; EXR stays linear and says nothing.
    let o = raypipe(dir.path(), &["render", "-o", "p.png", "--algo", "path", "--samples", "2", "--size", "16x16"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("exposure auto"), "{}", String::from_utf8_lossy(&o.stdout));
    let o = raypipe(dir.path(), &["render", "-o", "p.exr", "--algo", "path", "--samples", "2", "--size", "16x16"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("exposure"), "{}", String::from_utf8_lossy(&o.stdout));
    let o = raypipe(dir.path(), &["render", "-o", "c.png", "--clamp", "2"]);
    assert_one_line_error(&o, "path tracing only");
    let o = raypipe(dir.path(), &["render", "-o", "c.png", "--filter", "lanczos"]);
    assert!(!o.status.success() && stderr(&o).contains("unknown filter"), "{}", stderr(&o));
}

/// A scene with many warnings prints one line by default, every one with --verbose and
/// none with --quiet; the image is the same.
#[test]
fn long_warning_lists_fold_unless_verbose() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut mtl = String::new();
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for i in 0..5 {
        mtl += &format!("newmtl m{i}\nKd 0.5 0.5 0.5\nmap_Kd missing{i}.png\n");
        obj += &format!("usemtl m{i}\nf 1 2 3\n");
    }
    write(d, "m.mtl", &mtl);
    write(d, "s.obj", &obj);
    let count = |args: &[&str]| {
        let mut all = vec!["render", "s.obj", "--size", "8x8", "-o", "x.png"];
        all.extend_from_slice(args);
        let o = raypipe(d, &all);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o).lines().filter(|l| l.starts_with("warning:")).count()
    };
    assert_eq!(count(&[]), 1, "folded");
    assert!(count(&["--verbose"]) >= 5);
    assert_eq!(count(&["--quiet"]), 0);
    assert_eq!(count(&["-q"]), 0);
}

/// A first view that misses the scene says so: a wall seen from outside, a surface right
/// in front of the eye, a view of nothing; a good view says nothing.
#[test]
fn views_that_miss_the_scene_get_a_hint() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A 10 × 10 wall at z = 0 with a box behind it.
    let mut obj = String::from("v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3\nf 1 3 4\n");
    for (x, y, z) in
        [(-1, -1, -4), (1, -1, -4), (1, 1, -4), (-1, 1, -4), (-1, -1, -6), (1, -1, -6), (1, 1, -6), (-1, 1, -6)]
    {
        obj += &format!("v {x} {y} {z}\n");
    }
    obj += "f 5 6 7\nf 5 7 8\nf 9 10 11\nf 9 11 12\nf 5 6 10\nf 5 10 9\n";
    write(d, "wall.obj", &obj);
    let hint = |args: &[&str]| {
        let mut all = vec!["render", "wall.obj", "--size", "16x16", "-o", "x.png"];
        all.extend_from_slice(args);
        let o = raypipe(d, &all);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o).lines().filter(|l| l.starts_with("hint:")).map(String::from).collect::<Vec<_>>()
    };
    let outside = hint(&["--eye", "0,0,12", "--look-at", "0,0,0"]);
    assert!(outside.iter().any(|h| h.contains("mostly one surface")), "{outside:?}");
    let pressed = hint(&["--eye", "0,0,0.4", "--look-at", "0,0,-5", "--fov", "60"]);
    assert!(pressed.iter().any(|h| h.contains("blocks the view")), "{pressed:?}");
    let away = hint(&["--eye", "0,0,12", "--look-at", "0,0,30"]);
    assert!(away.iter().any(|h| h.contains("sees almost nothing")), "{away:?}");
    let eye_only = hint(&["--eye", "0,0,12"]);
    assert!(eye_only.iter().any(|h| h.contains("--eye without --look-at")), "{eye_only:?}");
    let good = hint(&["--eye", "8,3,-12", "--look-at", "0,0,-3"]);
    assert!(good.iter().all(|h| !h.contains("surface") && !h.contains("nothing")), "{good:?}");
}

#[cfg(not(feature = "mpi"))]
#[test]
fn render_mpi_without_the_mpi_feature_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let o = raypipe(dir.path(), &["render", "--mpi", "-o", "x.png"]);
    assert_one_line_error(&o, "built without MPI");
    assert!(only_files(dir.path()).is_empty());
}

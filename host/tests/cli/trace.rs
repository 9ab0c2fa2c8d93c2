//! `raypipe trace` and `raypipe rays`: ray batches as `.npy`, queries, fields and
//! malformed arrays.

use crate::common::*;
use std::path::Path;

/// Writes a little-endian float32 .npy array of the given shape.
pub(crate) fn write_npy(path: &Path, shape: &[usize], data: &[f32], descr: &str) {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// Reads the structured hits array back: (t, u, v, prim) per ray.
pub(crate) fn read_hits(path: &Path) -> Vec<(f32, f32, f32, i32)> {
    let bytes = std::fs::read(path).unwrap();
    let hl = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = String::from_utf8_lossy(&bytes[10..10 + hl]).into_owned();
    assert!(header.contains("('prim', '<i4')"), "{header}");
    bytes[10 + hl..]
        .chunks_exact(16)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            (f(0), f(4), f(8), i32::from_le_bytes([c[12], c[13], c[14], c[15]]))
        })
        .collect()
}

#[test]
fn trace_a_ray_batch_with_every_structure_and_packet_size() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("cornell_box.obj");
    let obj = obj.to_str().unwrap();
    // Rays of a view in 8×8 blocks, plus the scene's triangles.
    let o = raypipe(d, &["rays", "-o", "rays.npy", "--size", "32x24", "--block", "8", "--triangles", "tris.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut reference = None;
    for accel in ["grid", "kd", "bvh", "bvh4"] {
        for packet in ["1", "4", "16", "64"] {
            let o = raypipe(
                d,
                &["trace", obj, "--rays", "rays.npy", "--hits", "hits.npy", "--accel", accel, "--packet", packet],
            );
            assert!(o.status.success(), "{accel} {packet}: {}", stderr(&o));
            let hits = read_hits(&d.join("hits.npy"));
            assert_eq!(hits.len(), 32 * 24);
            let hit_count = hits.iter().filter(|h| h.3 >= 0).count();
            assert!(hit_count > 500, "most rays of the box view hit: {hit_count}");
            assert!(hits.iter().all(|h| h.3 < 32), "ids are input triangle ids");
            match &reference {
                None => reference = Some(hits),
                Some(r) => assert!(
                    r.iter().zip(&hits).all(|(a, b)| a.0.to_bits() == b.0.to_bits() && a.3 == b.3),
                    "{accel} with packets of {packet} differs"
                ),
            }
        }
    }
    // Images with leaf triangle blocks (the wide BVHs' single rays read them) give the
    // same hits; a structure without wide leaves keeps indexed triangles and says so.
    let reference = reference.unwrap();
    for accel in ["bvh4", "bvh8"] {
        let o = raypipe(d, &["build", obj, "--accel", accel, "--triangles", "blocks", "-o", "blocks.rpsi"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = raypipe(d, &["trace", "blocks.rpsi", "--rays", "rays.npy", "--hits", "hits.npy", "--packet", "1"]);
        assert!(String::from_utf8_lossy(&o.stdout).contains("leaf blocks"), "{}", stderr(&o));
        let hits = read_hits(&d.join("hits.npy"));
        assert!(
            reference.iter().zip(&hits).all(|(a, b)| a.0.to_bits() == b.0.to_bits() && a.3 == b.3),
            "{accel} blocks"
        );
    }
    let o = raypipe(d, &["build", obj, "--accel", "grid", "--triangles", "blocks", "-o", "grid.rpsi"]);
    assert!(o.status.success() && stderr(&o).contains("--triangles blocks applies to"), "{}", stderr(&o));
    // A ray above the blocks, straight down +z (N × 6 form), hits the back wall at z = 559.2.
    write_npy(&d.join("one.npy"), &[1, 6], &[100.0, 450.0, -800.0, 0.0, 0.0, 1.0], "<f4");
    assert!(raypipe(d, &["trace", obj, "--rays", "one.npy", "--hits", "one_hits.npy"]).status.success());
    let h = read_hits(&d.join("one_hits.npy"));
    assert!((h[0].0 - 1359.2).abs() < 1e-3, "{h:?}");
}

/// Ray queries: float64 input, rows that are no rays returned as misses
/// and counted, any-hit queries, optional fields, and the warning for incoherent packets.
#[test]
fn ray_queries_fields_and_invalid_rays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("cornell_box.obj");
    let obj = obj.to_str().unwrap();
    // Down the box from above the blocks; a NaN row; a zero direction; an empty interval;
    // the same ray with an interval too short to reach anything.
    let good = [100.0, 450.0, -800.0, 0.0, 0.0, 1.0, 0.0, f32::INFINITY];
    let mut rows = good.to_vec();
    rows.extend([f32::NAN, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0]);
    rows.extend([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    rows.extend([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 5.0, 1.0]);
    rows.extend([100.0, 450.0, -800.0, 0.0, 0.0, 1.0, 0.0, 10.0]);
    // As float64.
    let mut bytes = Vec::new();
    let mut header = "{'descr': '<f8', 'fortran_order': False, 'shape': (5, 8), }".to_string();
    while !(10 + header.len() + 1).is_multiple_of(64) {
        header.push(' ');
    }
    header.push('\n');
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in &rows {
        bytes.extend_from_slice(&(*v as f64).to_le_bytes());
    }
    std::fs::write(d.join("rays.npy"), bytes).unwrap();
    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "h.npy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("3 rows are not rays"), "{}", stderr(&o));
    let h = read_hits(&d.join("h.npy"));
    assert_eq!(h.len(), 5);
    assert!((h[0].0 - 1359.2).abs() < 1e-3 && h[0].3 >= 0, "{h:?}");
    assert!(h[1..].iter().all(|r| r.3 == -1 && r.0 == f32::INFINITY), "{h:?}");

    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "any.npy", "--query", "any"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let any = std::fs::read(d.join("any.npy")).unwrap();
    let hl = u16::from_le_bytes([any[8], any[9]]) as usize;
    assert!(String::from_utf8_lossy(&any[10..10 + hl]).contains("('occluded', 'u1')"));
    assert_eq!(&any[10 + hl..], &[1, 0, 0, 0, 0], "only the first ray is blocked");

    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "f.npy", "--fields", "prim,ng,ns,material"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let f = std::fs::read(d.join("f.npy")).unwrap();
    let hl = u16::from_le_bytes([f[8], f[9]]) as usize;
    let header = String::from_utf8_lossy(&f[10..10 + hl]).into_owned();
    assert!(header.contains("('ng', '<f4', (3,))") && header.contains("('material', '<i4')"), "{header}");
    let rec = &f[10 + hl..10 + hl + 32];
    let fl = |i: usize| f32::from_le_bytes(rec[i..i + 4].try_into().unwrap());
    // The back wall faces the ray: both normals along z, the shading one towards -z.
    assert!(fl(12).abs() > 0.99 && (fl(24) + 1.0).abs() < 1e-3, "{rec:?}");
    assert!(i32::from_le_bytes(rec[28..32].try_into().unwrap()) >= 0);
    assert_eq!(f.len() - 10 - hl, 5 * 32);

    // Object ids: the OBJ's `o` names in order (floor, light, ceiling, back_wall, …).
    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "o.npy", "--fields", "object"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let f = std::fs::read(d.join("o.npy")).unwrap();
    let hl = u16::from_le_bytes([f[8], f[9]]) as usize;
    assert!(String::from_utf8_lossy(&f[10..10 + hl]).contains("('object', '<i4')"));
    let ids: Vec<i32> = f[10 + hl..].chunks_exact(4).map(|c| i32::from_le_bytes(c.try_into().unwrap())).collect();
    assert_eq!(ids, [3, -1, -1, -1, -1], "the back wall is the fourth object");

    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "x.npy", "--fields", "t,colour"]);
    assert_one_line_error(&o, "unknown field 'colour'");
    let o = raypipe(d, &["trace", obj, "--rays", "rays.npy", "--hits", "x.npy", "--query", "any", "--fields", "t"]);
    assert_one_line_error(&o, "only 'occluded'");

    // Incoherent packets: random directions, traced as 4×4 packets, are warned about.
    let mut g = 12345u32;
    let mut next = || {
        g ^= g << 13;
        g ^= g >> 17;
        g ^= g << 5;
        g as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    let scattered: Vec<f32> = (0..64).flat_map(|_| [250.0, 250.0, 250.0, next(), next(), next()]).collect();
    write_npy(&d.join("scattered.npy"), &[64, 6], &scattered, "<f4");
    let o = raypipe(d, &["trace", obj, "--rays", "scattered.npy", "--hits", "s.npy", "--packet", "16"]);
    assert!(o.status.success() && stderr(&o).contains("incoherent"), "{}", stderr(&o));
    let o = raypipe(d, &["trace", obj, "--rays", "scattered.npy", "--hits", "s.npy"]);
    assert!(o.status.success() && !stderr(&o).contains("incoherent"), "{}", stderr(&o));
    // Single rays grouped by direction before the trace: the same records, in the file's
    // order, whatever the order asked for.
    let given = read_hits(&d.join("s.npy"));
    for order in ["input", "direction", "auto"] {
        let o = raypipe(d, &["trace", obj, "--rays", "scattered.npy", "--hits", "o.npy", "--order", order]);
        assert!(o.status.success(), "--order {order}: {}", stderr(&o));
        let got = read_hits(&d.join("o.npy"));
        assert!(got.len() == given.len() && got.iter().zip(&given).all(|(a, b)| format!("{a:?}") == format!("{b:?}")));
    }
    let o = raypipe(d, &["trace", obj, "--rays", "scattered.npy", "--hits", "o.npy", "--order", "sorted"]);
    assert!(!o.status.success() && stderr(&o).contains("--order"), "{}", stderr(&o));
}

#[test]
fn malformed_ray_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = fixtures().join("tetra.obj");
    let obj = obj.to_str().unwrap();
    let run = |name: &str| raypipe(d, &["trace", obj, "--rays", name, "--hits", "h.npy"]);
    write_npy(&d.join("cols.npy"), &[2, 5], &[0.0; 10], "<f4");
    assert_one_line_error(&run("cols.npy"), "5 columns");
    std::fs::write(d.join("i4.npy"), {
        let mut b = std::fs::read(d.join("cols.npy")).unwrap();
        let at = b.windows(3).position(|w| w == b"<f4").unwrap();
        b[at..at + 3].copy_from_slice(b"<i4");
        b
    })
    .unwrap();
    assert_one_line_error(&run("i4.npy"), "float64");
    std::fs::write(d.join("junk.npy"), b"not numpy").unwrap();
    assert_one_line_error(&run("junk.npy"), "junk.npy");
    assert_one_line_error(&run("missing.npy"), "missing.npy");
    assert!(!d.join("h.npy").exists());
}

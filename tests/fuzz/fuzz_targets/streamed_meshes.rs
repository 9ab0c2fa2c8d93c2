//! Any bytes as an OBJ or PLY file read as a stream (the first byte chooses): its
//! tables and faces or a one-line error, never a panic; when it reads, it hands on
//! exactly the triangles its first pass counted (OBJ), and only vertices it holds.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&kind, body)) = data.split_first() else { return };
    let dir = std::env::temp_dir().join(format!("raypipe-fuzz-streams-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = kind % 2 == 0;
    let path = dir.join(if obj { "f.obj" } else { "f.ply" });
    std::fs::write(&path, body).unwrap();
    let budget = 64 << 20;
    let result = if obj {
        raypipe::input::obj_stream::ObjStream::open(&path, budget).and_then(|s| {
            let mut n = 0u64;
            s.faces(&mut |t| {
                assert!((t.material as usize) < s.tables.materials.len(), "material in range");
                n += 1;
                Ok(())
            })?;
            assert_eq!(n, s.triangles, "the faces make the triangles the survey counted");
            Ok(())
        })
    } else {
        raypipe::input::ply_stream::PlyStream::open(&path, budget).and_then(|mut s| {
            let nv = s.positions.len();
            s.faces(&mut |t| {
                assert!(t.iter().all(|&v| (v as usize) < nv), "faces name vertices that exist");
                Ok(())
            })?;
            Ok(())
        })
    };
    if let Err(e) = result {
        assert!(!e.to_string().contains('\n'), "one-line error: {e}");
    }
});

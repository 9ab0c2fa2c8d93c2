//! A check of an OBJ file's face indices before tobj reads it: tobj drops a texture
//! coordinate or normal index that names nothing, silently, so a face
//! that names a missing `vt` or `vn` (or `v`) is reported here, with its line. OBJ
//! indices count from 1 and refer to the elements defined so far; negative ones count
//! back from the last.

use anyhow::{bail, Result};

/// Checks every `f` line of `text` (`name` for messages).
pub fn check_face_indices(name: &str, text: &[u8]) -> Result<()> {
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    for (number, line) in text.split(|&b| b == b'\n').enumerate() {
        let line = String::from_utf8_lossy(line);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => v += 1,
            Some("vt") => vt += 1,
            Some("vn") => vn += 1,
            Some("f") => {
                for word in words {
                    for (k, part) in word.split('/').enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let Ok(i) = part.parse::<i64>() else { continue };
                        let (count, what) = match k {
                            0 => (v, "vertex"),
                            1 => (vt, "texture coordinate"),
                            _ => (vn, "normal"),
                        };
                        if i == 0 || i > count || -i > count {
                            bail!(
                                "{name}: malformed OBJ: line {}: the face names {what} {i}, but {count} are defined",
                                number + 1
                            );
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_naming_missing_elements_are_reported_with_their_line() {
        let ok = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 -1/-1/-1\n";
        check_face_indices("a.obj", ok.as_bytes()).unwrap();
        for (bad, what) in [
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/2 2/1 3/1\n", "texture coordinate 2, but 1"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n", "normal 1, but 0"),
            ("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "vertex 3, but 2"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-2 2/1 3/1\n", "texture coordinate -2"),
        ] {
            let e = check_face_indices("a.obj", bad.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(what) && e.contains("line ") && !e.contains('\n'), "{e}");
        }
    }
}

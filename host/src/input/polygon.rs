//! Triangulation of OBJ polygons. Small polygons (up to [`FAN_MAX`] vertices) become
//! fans from their first vertex, exactly as tobj made them. Larger ones are split by
//! halving: the polygon `i..=j` gives the triangle `(i, m, j)` with `m` its middle vertex
//! and recurses into `i..=m` and `m..=j`. A fan of an `n`-gon has `n − 3` diagonals from
//! one vertex, nearly all as long as the polygon is wide, and every one of those slivers
//! crosses a spatial structure from side to side: building a grid over a 20,000-vertex
//! polygon took 22 s and 91 M list entries. Halving's diagonals on level
//! `k` are `2^k` chords of about `1/2^k` of the outline each, so their total length is
//! the outline's times `log2 n`, and the references a grid or tree makes grow as
//! `n log n`. Both keep the polygon's winding, and both assume (as OBJ does) a convex or
//! at least star-shaped face.

/// Polygons with at most this many vertices are fans (quads split on `v0–v2`, as before).
pub const FAN_MAX: usize = 8;

/// Calls `emit` with the `n − 2` triangles of the polygon `poly` (indices in order).
pub fn triangulate(poly: &[u32], mut emit: impl FnMut([u32; 3])) {
    let n = poly.len();
    if n < 3 {
        return;
    }
    if n <= FAN_MAX {
        for k in 1..n - 1 {
            emit([poly[0], poly[k], poly[k + 1]]);
        }
        return;
    }
    // (i, j): the sub-polygon of vertices i..=j, closed by the chord j–i. An explicit
    // stack (depth log2 n) rather than recursion.
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j < i + 2 {
            continue;
        }
        let m = (i + j).div_ceil(2);
        emit([poly[i], poly[m], poly[j]]);
        stack.push((m, j));
        stack.push((i, m));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tris(n: u32) -> Vec<[u32; 3]> {
        let poly: Vec<u32> = (0..n).collect();
        let mut out = Vec::new();
        triangulate(&poly, |t| out.push(t));
        out
    }

    #[test]
    fn small_polygons_are_the_fans_tobj_made() {
        assert_eq!(tris(3), vec![[0, 1, 2]]);
        assert_eq!(tris(4), vec![[0, 1, 2], [0, 2, 3]]);
        assert!(tris(2).is_empty());
    }

    /// Every polygon gives n − 2 triangles that keep its winding (increasing indices in
    /// cyclic order) and together cover each outline edge exactly once.
    #[test]
    fn large_polygons_split_into_n_minus_2_triangles_covering_the_outline() {
        for n in [9u32, 10, 17, 100, 1001] {
            let t = tris(n);
            assert_eq!(t.len(), n as usize - 2);
            let mut edges = std::collections::HashMap::new();
            for [a, b, c] in &t {
                assert!(a < b && b < c, "{n}: {:?} keeps the winding", [a, b, c]);
                for (p, q) in [(a, b), (b, c), (a, c)] {
                    *edges.entry((*p, *q)).or_insert(0) += 1;
                }
            }
            for k in 0..n {
                let e = if k + 1 < n { (k, k + 1) } else { (0, n - 1) };
                assert_eq!(edges.get(&e), Some(&1), "{n}: outline edge {e:?}");
            }
            // Interior diagonals are shared by exactly two triangles.
            let outline = |&(p, q): &(u32, u32)| q == p + 1 || (p == 0 && q == n - 1);
            assert!(edges.iter().filter(|(e, _)| !outline(e)).all(|(_, &c)| c == 2));
        }
    }
}

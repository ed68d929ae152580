//! Marching Cubes case tables, generated at start-up from first principles and shared by the CPU
//! engine and the GPU shaders (uploaded as storage buffers), so both triangulate every cell the
//! same way.
//!
//! Conventions (used everywhere a cell is touched):
//! - corner `c` (0..8) of the cell at grid point `(i, j, k)` sits at `(i + (c & 1), j + (c >> 1 & 1),
//!   k + (c >> 2 & 1))`; the cell's case byte has bit `c` set when the density at that corner is
//!   `>= I` ("inside");
//! - edge `e` (0..12) runs along axis `e / 4` (0 = x, 1 = y, 2 = z) from the corner
//!   [`EDGE_CORNERS`]`[e][0]`; its vertex belongs to that grid point and axis, so neighbouring cells
//!   share it;
//! - on a face whose four corners alternate inside/outside, each inside corner is cut off on its
//!   own (the outside corners connect across the face). The rule depends only on the face, so two
//!   cells that share a face cut it identically and the mesh is closed;
//! - each loop of crossed edges is triangulated without diagonals that lie in a cell face, so no
//!   edge is shared by more than two triangles, and triangles wind counter-clockwise seen from
//!   outside the surface (low density).

use std::sync::OnceLock;

/// The two corners of each edge; the first is the corner the edge's vertex belongs to.
pub const EDGE_CORNERS: [[u8; 2]; 12] = [
    [0, 1],
    [2, 3],
    [4, 5],
    [6, 7],
    [0, 2],
    [1, 3],
    [4, 6],
    [5, 7],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Offset `(dx, dy, dz)` of corner `c` from the cell's base grid point.
pub const fn corner_offset(c: u8) -> [u32; 3] {
    [(c & 1) as u32, ((c >> 1) & 1) as u32, ((c >> 2) & 1) as u32]
}

/// Axis (0 = x, 1 = y, 2 = z) along which edge `e` runs.
pub const fn edge_axis(e: u8) -> u32 {
    (e / 4) as u32
}

/// Marching Cubes triangles for all 256 cases.
#[derive(Debug, Clone)]
pub struct McTables {
    /// `case_start[case]..case_start[case + 1]` indexes [`McTables::triangles`]; 257 entries.
    pub case_start: Vec<u32>,
    /// Triangles as three cell-edge indices (0..12), wound counter-clockwise seen from outside.
    pub triangles: Vec<[u8; 3]>,
    /// Bit `e` set when edge `e` of the cell is crossed, per case.
    pub crossed_edges: Vec<u16>,
}

impl McTables {
    /// The shared tables (built once).
    pub fn get() -> &'static McTables {
        static TABLES: OnceLock<McTables> = OnceLock::new();
        TABLES.get_or_init(build_tables)
    }

    /// Triangles of one case.
    pub fn case_triangles(&self, case: u8) -> &[[u8; 3]] {
        let c = case as usize;
        &self.triangles[self.case_start[c] as usize..self.case_start[c + 1] as usize]
    }

    /// Largest number of triangles any case emits.
    pub fn max_triangles_per_cell(&self) -> usize {
        (0..256)
            .map(|c| self.case_triangles(c as u8).len())
            .max()
            .unwrap_or(0)
    }

    /// Triangle edges flattened to `u32` (three per triangle) for upload to the GPU.
    pub fn triangles_flat_u32(&self) -> Vec<u32> {
        self.triangles
            .iter()
            .flat_map(|t| t.map(u32::from))
            .collect()
    }
}

fn corner_pos(c: u8) -> [i32; 3] {
    let o = corner_offset(c);
    [o[0] as i32, o[1] as i32, o[2] as i32]
}

fn edge_between(a: u8, b: u8) -> u8 {
    EDGE_CORNERS
        .iter()
        .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
        .expect("corners share an edge") as u8
}

/// The six faces, each as four corners counter-clockwise seen from outside the cell.
fn faces() -> Vec<[u8; 4]> {
    let mut out = Vec::new();
    for axis in 0..3 {
        for side in 0..2u8 {
            let mut corners: Vec<u8> = (0..8u8).filter(|&c| (c >> axis) & 1 == side).collect();
            // Put them in cyclic order: 0, a, a+b, b in the two other axes.
            let (a, b) = match axis {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            let key = |c: &u8| {
                let p = corner_pos(*c);
                match (p[a], p[b]) {
                    (0, 0) => 0,
                    (1, 0) => 1,
                    (1, 1) => 2,
                    _ => 3,
                }
            };
            corners.sort_by_key(key);
            let p: Vec<[i32; 3]> = corners.iter().map(|&c| corner_pos(c)).collect();
            let d1 = sub(p[1], p[0]);
            let d2 = sub(p[2], p[1]);
            let n = cross(d1, d2);
            let outward = if side == 0 { -1 } else { 1 };
            let mut face = [corners[0], corners[1], corners[2], corners[3]];
            if n[axis] * outward < 0 {
                face.reverse();
            }
            out.push(face);
        }
    }
    out
}

fn sub(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Faces (indices into [`faces`]) that contain edge `e`.
fn edge_faces(all_faces: &[[u8; 4]], e: u8) -> Vec<usize> {
    let [a, b] = EDGE_CORNERS[e as usize];
    (0..all_faces.len())
        .filter(|&f| all_faces[f].contains(&a) && all_faces[f].contains(&b))
        .collect()
}

fn build_tables() -> McTables {
    let all_faces = faces();
    let mut case_start = Vec::with_capacity(257);
    let mut triangles = Vec::new();
    let mut crossed_edges = Vec::with_capacity(256);
    for case in 0..256u32 {
        case_start.push(triangles.len() as u32);
        let inside = |c: u8| (case >> c) & 1 == 1;
        let mut crossed = 0u16;
        for (e, [a, b]) in EDGE_CORNERS.iter().enumerate() {
            if inside(*a) != inside(*b) {
                crossed |= 1 << e;
            }
        }
        crossed_edges.push(crossed);
        // Directed segments on each face: from the edge where the boundary walk leaves an
        // inside arc to the edge where it entered it, which keeps the inside on the left.
        let mut next = [u8::MAX; 12];
        for face in &all_faces {
            for s in 0..4 {
                let c = face[s];
                let n = face[(s + 1) % 4];
                if !inside(c) && inside(n) {
                    // Entering an inside arc at edge (c, n); find where it leaves.
                    let enter = edge_between(c, n);
                    let mut t = (s + 1) % 4;
                    while inside(face[(t + 1) % 4]) {
                        t = (t + 1) % 4;
                    }
                    let leave = edge_between(face[t], face[(t + 1) % 4]);
                    next[leave as usize] = enter;
                }
            }
        }
        // Chain the segments into loops and triangulate each.
        let mut used = 0u16;
        for start in 0..12u8 {
            if crossed & (1 << start) == 0 || used & (1 << start) != 0 {
                continue;
            }
            let mut loop_edges = Vec::new();
            let mut e = start;
            loop {
                used |= 1 << e;
                loop_edges.push(e);
                e = next[e as usize];
                if e == start {
                    break;
                }
            }
            triangulate(&all_faces, &loop_edges, &mut triangles);
        }
    }
    case_start.push(triangles.len() as u32);
    let mut tables = McTables {
        case_start,
        triangles,
        crossed_edges,
    };
    orient_outward(&mut tables);
    tables
}

/// True when the segment between the vertices on edges `a` and `b` may be a triangle edge:
/// either both lie on no common face (the segment crosses the cell's interior) or they are
/// consecutive on the loop (a segment that the neighbouring cell shares).
fn diagonal_ok(all_faces: &[[u8; 4]], a: u8, b: u8) -> bool {
    let fa = edge_faces(all_faces, a);
    let fb = edge_faces(all_faces, b);
    !fa.iter().any(|f| fb.contains(f))
}

/// Triangulates a loop of edge vertices, never using a diagonal that lies in a cell face.
fn triangulate(all_faces: &[[u8; 4]], poly: &[u8], out: &mut Vec<[u8; 3]>) {
    fn go(all_faces: &[[u8; 4]], poly: &[u8], out: &mut Vec<[u8; 3]>) -> bool {
        let n = poly.len();
        if n == 3 {
            out.push([poly[0], poly[1], poly[2]]);
            return true;
        }
        // Triangle (poly[0], poly[1], poly[k]) splits off the chains on either side.
        for k in 2..n {
            let left_ok = k == 2 || diagonal_ok(all_faces, poly[1], poly[k]);
            let right_ok = k == n - 1 || diagonal_ok(all_faces, poly[0], poly[k]);
            if !(left_ok && right_ok) {
                continue;
            }
            let mark = out.len();
            out.push([poly[0], poly[1], poly[k]]);
            let left: Vec<u8> = poly[1..=k].to_vec();
            let mut right: Vec<u8> = poly[k..].to_vec();
            right.push(poly[0]);
            let left_done = left.len() < 3 || go(all_faces, &left, out);
            let right_done = left_done && (right.len() < 3 || go(all_faces, &right, out));
            if left_done && right_done {
                return true;
            }
            out.truncate(mark);
        }
        false
    }
    for r in 0..poly.len() {
        let mut rotated = poly[r..].to_vec();
        rotated.extend_from_slice(&poly[..r]);
        if go(all_faces, &rotated, out) {
            return;
        }
    }
    panic!("no face-free triangulation of loop {poly:?}");
}

/// Makes triangles wind counter-clockwise seen from outside: checked on case 1 (only corner 0
/// inside), whose triangle must face away from corner 0; the construction orients every loop the
/// same way, so one check decides them all.
fn orient_outward(tables: &mut McTables) {
    let mid = |e: u8| {
        let [a, b] = EDGE_CORNERS[e as usize];
        let (pa, pb) = (corner_pos(a), corner_pos(b));
        [pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]]
    };
    let t = tables.case_triangles(1)[0];
    let n = cross(sub(mid(t[1]), mid(t[0])), sub(mid(t[2]), mid(t[0])));
    if n[0] + n[1] + n[2] < 0 {
        for tri in &mut tables.triangles {
            tri.swap(1, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_full_cases_have_no_triangles() {
        let t = McTables::get();
        assert!(t.case_triangles(0).is_empty());
        assert!(t.case_triangles(255).is_empty());
        assert_eq!(t.case_start.len(), 257);
    }

    #[test]
    fn every_crossed_edge_is_used_and_no_other() {
        let t = McTables::get();
        for case in 0..256usize {
            let mut used = 0u16;
            for tri in t.case_triangles(case as u8) {
                for &e in tri {
                    used |= 1 << e;
                }
            }
            assert_eq!(used, t.crossed_edges[case], "case {case}");
        }
    }

    #[test]
    fn complement_cases_have_same_triangle_count_or_differ_only_by_ambiguity() {
        // A single inside corner and a single outside corner both give one triangle.
        let t = McTables::get();
        for c in 0..8u8 {
            assert_eq!(t.case_triangles(1 << c).len(), 1);
            assert_eq!(t.case_triangles(!(1u8 << c)).len(), 1);
        }
        assert!(t.max_triangles_per_cell() <= 10);
    }
}

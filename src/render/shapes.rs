//! Simple meshes built in code: an icosphere, for tests and as a stand-in before data loads.

use std::collections::HashMap;

use glam::Vec3;

use crate::surface::Mesh;

/// A sphere of `radius` Å around `centre`, made by subdividing an icosahedron `subdivisions`
/// times (20 * 4^n triangles), with outward normals, counter-clockwise triangles and one
/// `colour` (linear RGB) per vertex, or a colour by direction when `None`.
pub fn icosphere(centre: Vec3, radius: f32, subdivisions: u32, colour: Option<[f32; 3]>) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut dirs: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, dirs: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                dirs.push((dirs[a as usize] + dirs[b as usize]).normalize());
                dirs.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut dirs);
            let bc = midpoint(b, c, &mut dirs);
            let ca = midpoint(c, a, &mut dirs);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    Mesh {
        positions: dirs.iter().map(|d| centre + *d * radius).collect(),
        normals: dirs.clone(),
        colours: dirs
            .iter()
            .map(|d| colour.unwrap_or([0.5 + 0.5 * d.x, 0.5 + 0.5 * d.y, 0.5 + 0.5 * d.z]))
            .collect(),
        indices: tris.into_iter().flatten().collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_is_closed_outward_and_near_the_sphere_volume() {
        let m = icosphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 3, None);
        assert_eq!(m.triangle_count(), 20 * 64);
        assert!(m.is_closed());
        assert_eq!(m.euler_characteristic(), 2);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 8.0;
        let v = m.volume();
        assert!(v > 0.97 * exact && v < exact, "volume {v} vs {exact}");
    }
}

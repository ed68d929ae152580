//! The mesh writers (PLY, OBJ, STL, GLB) on a mesh with known geometry: each file is parsed back
//! by an independent reader written here (and, for glTF, the `gltf-json` crate's deserialiser
//! and validator), and its counts, positions, normals, colours and enclosed volume must match.

use std::fs;
use std::path::Path;

use glam::Vec3;
use mdsurf::export::{self, MeshFormat, linear_to_srgb8};
use mdsurf::surface::Mesh;

/// A regular octahedron with vertices at ±1 on each axis: 6 vertices, 8 outward triangles,
/// volume 4/3 Å³, area 4√3 Å²; every vertex has its own colour.
fn octahedron() -> Mesh {
    let positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut indices = Vec::new();
    for sx in [0u32, 1] {
        for sy in [0u32, 1] {
            for sz in [0u32, 1] {
                let (x, y, z) = (sx, 2 + sy, 4 + sz);
                // Odd number of negative axes flips the winding.
                if (sx + sy + sz) % 2 == 0 {
                    indices.extend([x, y, z]);
                } else {
                    indices.extend([x, z, y]);
                }
            }
        }
    }
    let colours = (0..6)
        .map(|i| [i as f32 / 5.0, 1.0 - i as f32 / 5.0, 0.25])
        .collect();
    Mesh {
        normals: positions.clone(),
        positions,
        colours,
        indices,
    }
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// Signed volume of triangles given as three points each.
fn volume(tris: &[[Vec3; 3]]) -> f64 {
    tris.iter()
        .map(|[a, b, c]| a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0)
        .sum()
}

fn write(dir: &Path, name: &str, mesh: &Mesh) -> Vec<u8> {
    let path = dir.join(name);
    export::write_mesh(&path, mesh).unwrap();
    fs::read(&path).unwrap()
}

#[test]
fn octahedron_is_what_the_tests_assume() {
    let m = octahedron();
    assert!(m.is_closed());
    assert!((m.volume() - 4.0 / 3.0).abs() < 1e-6, "{}", m.volume());
    assert!((m.area() - 4.0 * 3f64.sqrt()).abs() < 1e-5);
}

#[test]
fn ply_is_binary_little_endian_with_normals_and_colours() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron();
    let bytes = write(dir.path(), "m.ply", &mesh);
    let end = b"end_header\n";
    let header_len = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).unwrap();
    let lines: Vec<&str> = header
        .lines()
        .filter(|l| !l.starts_with("comment"))
        .collect();
    assert_eq!(
        lines,
        [
            "ply",
            "format binary_little_endian 1.0",
            "element vertex 6",
            "property float x",
            "property float y",
            "property float z",
            "property float nx",
            "property float ny",
            "property float nz",
            "property uchar red",
            "property uchar green",
            "property uchar blue",
            "element face 8",
            "property list uchar int vertex_indices",
            "end_header",
        ]
    );
    assert_eq!(bytes.len(), header_len + 6 * 27 + 8 * 13);
    let body = &bytes[header_len..];
    let mut verts = Vec::new();
    for i in 0..6 {
        let r = &body[i * 27..(i + 1) * 27];
        let p = Vec3::new(f32_at(r, 0), f32_at(r, 4), f32_at(r, 8));
        let n = Vec3::new(f32_at(r, 12), f32_at(r, 16), f32_at(r, 20));
        assert_eq!(p, mesh.positions[i]);
        assert_eq!(n, mesh.normals[i]);
        assert_eq!(&r[24..27], &mesh.colours[i].map(linear_to_srgb8));
        verts.push(p);
    }
    let faces = &body[6 * 27..];
    let mut tris = Vec::new();
    for f in faces.chunks_exact(13) {
        assert_eq!(f[0], 3);
        let idx = [1, 5, 9].map(|o| u32_at(f, o) as usize);
        tris.push(idx.map(|i| verts[i]));
    }
    assert!((volume(&tris) - 4.0 / 3.0).abs() < 1e-6);
}

#[test]
fn obj_has_vertices_colours_normals_and_one_based_faces() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron();
    let text = String::from_utf8(write(dir.path(), "m.obj", &mesh)).unwrap();
    let mut verts = Vec::new();
    let mut normals = 0;
    let mut tris = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let v: Vec<f32> = it.map(|x| x.parse().unwrap()).collect();
                assert_eq!(v.len(), 6, "v x y z r g b: {line}");
                assert!(v[3..].iter().all(|c| (0.0..=1.0).contains(c)));
                verts.push(Vec3::new(v[0], v[1], v[2]));
            }
            Some("vn") => normals += 1,
            Some("f") => {
                let idx: Vec<usize> = it
                    .map(|c| {
                        let (v, n) = c.split_once("//").unwrap();
                        assert_eq!(v, n);
                        v.parse::<usize>().unwrap()
                    })
                    .collect();
                assert_eq!(idx.len(), 3);
                assert!(idx.iter().all(|&i| (1..=6).contains(&i)));
                tris.push(idx);
            }
            _ => {}
        }
    }
    assert_eq!((verts.len(), normals, tris.len()), (6, 6, 8));
    let tris: Vec<[Vec3; 3]> = tris
        .iter()
        .map(|t| [verts[t[0] - 1], verts[t[1] - 1], verts[t[2] - 1]])
        .collect();
    assert!((volume(&tris) - 4.0 / 3.0).abs() < 1e-5);
}

#[test]
fn stl_is_binary_with_outward_unit_face_normals() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = write(dir.path(), "m.STL", &octahedron());
    assert!(!bytes.starts_with(b"solid"));
    assert_eq!(u32_at(&bytes, 80), 8);
    assert_eq!(bytes.len(), 84 + 8 * 50);
    let mut tris = Vec::new();
    for r in bytes[84..].chunks_exact(50) {
        let v = |k: usize| {
            Vec3::new(
                f32_at(r, k * 12),
                f32_at(r, k * 12 + 4),
                f32_at(r, k * 12 + 8),
            )
        };
        let (n, a, b, c) = (v(0), v(1), v(2), v(3));
        assert!((n.length() - 1.0).abs() < 1e-5);
        assert!(n.dot((a + b + c) / 3.0) > 0.0, "normal points inward");
        tris.push([a, b, c]);
    }
    assert!((volume(&tris) - 4.0 / 3.0).abs() < 1e-6);
}

#[test]
fn glb_parses_validates_and_holds_the_mesh() {
    use gltf_json::validation::Validate;
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron();
    let bytes = write(dir.path(), "m.glb", &mesh);
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(&bytes, 4), 2);
    assert_eq!(u32_at(&bytes, 8) as usize, bytes.len());
    assert_eq!(bytes.len() % 4, 0);
    let json_len = u32_at(&bytes, 12) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    let root = gltf_json::Root::from_slice(&bytes[20..20 + json_len]).unwrap();
    let mut errors = Vec::new();
    root.validate(&root, gltf_json::Path::new, &mut |path, err| {
        errors.push(format!("{}: {err}", path()))
    });
    assert!(errors.is_empty(), "{errors:?}");
    let bin_at = 20 + json_len;
    let bin_len = u32_at(&bytes, bin_at) as usize;
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    let bin = &bytes[bin_at + 8..bin_at + 8 + bin_len];
    assert!(root.buffers[0].byte_length.0 as usize <= bin_len);

    let prim = &root.meshes[0].primitives[0];
    let accessor = |sem: gltf_json::mesh::Semantic| {
        let id = prim.attributes[&gltf_json::validation::Checked::Valid(sem)];
        &root.accessors[id.value()]
    };
    let read_vec3s = |acc: &gltf_json::Accessor| -> Vec<Vec3> {
        let view = &root.buffer_views[acc.buffer_view.unwrap().value()];
        let off = view.byte_offset.map_or(0, |o| o.0 as usize);
        (0..acc.count.0 as usize)
            .map(|i| {
                let at = off + i * 12;
                Vec3::new(f32_at(bin, at), f32_at(bin, at + 4), f32_at(bin, at + 8))
            })
            .collect()
    };
    let pos = accessor(gltf_json::mesh::Semantic::Positions);
    assert_eq!(pos.count.0, 6);
    assert_eq!(
        pos.min.as_ref().unwrap(),
        &gltf_json::Value::from(vec![-1.0, -1.0, -1.0])
    );
    assert_eq!(read_vec3s(pos), mesh.positions);
    assert_eq!(
        read_vec3s(accessor(gltf_json::mesh::Semantic::Normals)),
        mesh.normals
    );
    let colours = read_vec3s(accessor(gltf_json::mesh::Semantic::Colors(0)));
    assert_eq!(colours[5].to_array(), mesh.colours[5]);
    let idx = &root.accessors[prim.indices.unwrap().value()];
    let view = &root.buffer_views[idx.buffer_view.unwrap().value()];
    let off = view.byte_offset.map_or(0, |o| o.0 as usize);
    let indices: Vec<u32> = (0..idx.count.0 as usize)
        .map(|i| u32_at(bin, off + 4 * i))
        .collect();
    assert_eq!(indices, mesh.indices);
}

#[test]
fn empty_meshes_give_valid_files_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    for format in MeshFormat::ALL {
        let name = format!("empty.{format}");
        let bytes = write(dir.path(), &name, &Mesh::default());
        match format {
            MeshFormat::Ply => {
                let text = String::from_utf8_lossy(&bytes);
                assert!(text.contains("element vertex 0\n") && text.contains("element face 0\n"));
                assert!(text.ends_with("end_header\n"));
            }
            MeshFormat::Stl => assert_eq!(bytes.len(), 84),
            MeshFormat::Glb => {
                let json_len = u32_at(&bytes, 12) as usize;
                assert!(gltf_json::Root::from_slice(&bytes[20..20 + json_len]).is_ok());
                assert_eq!(u32_at(&bytes, 8) as usize, bytes.len());
            }
            MeshFormat::Obj => assert!(!String::from_utf8_lossy(&bytes).contains("\nf ")),
        }
    }
}

#[test]
fn srgb_encoding_hits_the_ends_and_the_middle() {
    assert_eq!(linear_to_srgb8(0.0), 0);
    assert_eq!(linear_to_srgb8(1.0), 255);
    assert_eq!(linear_to_srgb8(f32::NAN), 0);
    // Linear 0.2140 is sRGB 0.5 (about 128).
    assert!((127..=129).contains(&linear_to_srgb8(0.214)));
}

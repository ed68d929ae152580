//! glTF 2.0 binary (`.glb`) writer: one mesh with POSITION (with the min/max the spec requires),
//! NORMAL, COLOR_0 (linear RGB floats) and u32 indices, in one buffer. The JSON is built with
//! the `gltf-json` crate (typed, spec-checked structures); the GLB container (12-byte header,
//! JSON chunk padded with spaces, BIN chunk padded with zeros, all 4-byte aligned) is written
//! here.

use std::collections::BTreeMap;
use std::io::{self, Write};

use glam::Vec3;
use gltf_json as json;
use json::validation::{Checked, USize64};

use super::too_large;
use crate::surface::Mesh;

/// `glTF` in little-endian: the GLB magic.
pub const GLB_MAGIC: u32 = 0x4654_6C67;
/// Chunk type of the JSON chunk (`JSON`).
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type of the binary chunk (`BIN\0`).
pub const CHUNK_BIN: u32 = 0x004E_4942;

/// Writes `mesh` as a binary glTF 2.0 file. An empty mesh gives a valid file with an empty node.
pub fn write_glb(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let (root, bin) = build(mesh)?;
    let mut json_bytes = json::serialize::to_vec(&root).map_err(io::Error::other)?;
    pad_to_4(&mut json_bytes, b' ');
    let bin_padded = bin.len().next_multiple_of(4);
    let mut total = 12 + 8 + json_bytes.len();
    if !bin.is_empty() {
        total += 8 + bin_padded;
    }
    let total = u32::try_from(total).map_err(|_| too_large("a GLB file (4 GiB)"))?;

    w.write_all(&GLB_MAGIC.to_le_bytes())?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(json_bytes.len() as u32).to_le_bytes())?;
    w.write_all(&CHUNK_JSON.to_le_bytes())?;
    w.write_all(&json_bytes)?;
    if !bin.is_empty() {
        w.write_all(&(bin_padded as u32).to_le_bytes())?;
        w.write_all(&CHUNK_BIN.to_le_bytes())?;
        w.write_all(&bin)?;
        w.write_all(&vec![0u8; bin_padded - bin.len()])?;
    }
    Ok(())
}

fn pad_to_4(v: &mut Vec<u8>, with: u8) {
    v.resize(v.len().next_multiple_of(4), with);
}

/// The glTF document and its binary buffer for `mesh`.
fn build(mesh: &Mesh) -> io::Result<(json::Root, Vec<u8>)> {
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(format!("mdsurf {}", env!("CARGO_PKG_VERSION"))),
            ..Default::default()
        },
        ..Default::default()
    };
    let node = json::Node {
        mesh: None,
        ..Default::default()
    };
    if mesh.triangle_count() == 0 || mesh.vertex_count() == 0 {
        let node = root.push(node);
        let scene = root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            nodes: vec![node],
        });
        root.scene = Some(scene);
        return Ok((root, Vec::new()));
    }
    let n = mesh.vertex_count();
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));

    // Layout: positions, normals, colours (12 bytes per vertex each), then indices; every
    // section starts on a 4-byte boundary because all elements are 4 bytes.
    let mut bin = Vec::with_capacity(n * 36 + mesh.indices.len() * 4);
    let mut views = Vec::new();
    let mut section = |bin: &mut Vec<u8>, fill: &mut dyn FnMut(&mut Vec<u8>)| {
        let start = bin.len();
        fill(bin);
        views.push((start, bin.len() - start));
    };
    section(&mut bin, &mut |b| {
        for p in &mesh.positions {
            push_f32s(b, p.to_array());
        }
    });
    section(&mut bin, &mut |b| {
        for i in 0..n {
            let v = mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
            // NORMAL must be unit length: fall back to +z where the gradient vanished.
            let u = v.try_normalize().unwrap_or(Vec3::Z);
            push_f32s(b, u.to_array());
        }
    });
    section(&mut bin, &mut |b| {
        for i in 0..n {
            let c = mesh.colours.get(i).copied().unwrap_or([1.0; 3]);
            push_f32s(
                b,
                c.map(|x| {
                    if x.is_finite() {
                        x.clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                }),
            );
        }
    });
    section(&mut bin, &mut |b| {
        for &i in &mesh.indices {
            b.extend_from_slice(&i.to_le_bytes());
        }
    });
    if u32::try_from(bin.len()).is_err() {
        return Err(too_large("a GLB file (4 GiB)"));
    }

    let buffer = root.push(json::Buffer {
        byte_length: USize64::from(bin.len()),
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let targets = [
        json::buffer::Target::ArrayBuffer,
        json::buffer::Target::ArrayBuffer,
        json::buffer::Target::ArrayBuffer,
        json::buffer::Target::ElementArrayBuffer,
    ];
    let view_ids: Vec<_> = views
        .iter()
        .zip(targets)
        .map(|(&(offset, len), target)| {
            root.push(json::buffer::View {
                buffer,
                byte_length: USize64::from(len),
                byte_offset: Some(USize64::from(offset)),
                byte_stride: None,
                target: Some(Checked::Valid(target)),
                extensions: None,
                extras: Default::default(),
            })
        })
        .collect();

    let mut accessor = |view, count: usize, ty, component, min_max: Option<(Vec3, Vec3)>| {
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Checked::Valid(ty),
            min: min_max.map(|(lo, _)| json::Value::from(lo.to_array().to_vec())),
            max: min_max.map(|(_, hi)| json::Value::from(hi.to_array().to_vec())),
            normalized: false,
            sparse: None,
        })
    };
    use json::accessor::{ComponentType as C, Type as T};
    let pos = accessor(view_ids[0], n, T::Vec3, C::F32, Some((lo, hi)));
    let nrm = accessor(view_ids[1], n, T::Vec3, C::F32, None);
    let col = accessor(view_ids[2], n, T::Vec3, C::F32, None);
    let idx = accessor(view_ids[3], mesh.indices.len(), T::Scalar, C::U32, None);

    let mut attributes = BTreeMap::new();
    attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), pos);
    attributes.insert(Checked::Valid(json::mesh::Semantic::Normals), nrm);
    attributes.insert(Checked::Valid(json::mesh::Semantic::Colors(0)), col);
    let gmesh = root.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        primitives: vec![json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(idx),
            material: None,
            mode: Checked::Valid(json::mesh::Mode::Triangles),
            targets: None,
        }],
        weights: None,
    });
    let node = root.push(json::Node {
        mesh: Some(gmesh),
        ..node
    });
    let scene = root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        nodes: vec![node],
    });
    root.scene = Some(scene);
    Ok((root, bin))
}

fn push_f32s<const N: usize>(b: &mut Vec<u8>, v: [f32; N]) {
    for x in v {
        b.extend_from_slice(&x.to_le_bytes());
    }
}

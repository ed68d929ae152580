//! glTF 2.0 binary (`.glb`) writer. A static file ([`write_glb`]) holds one mesh with POSITION
//! (with the min/max the spec requires), NORMAL, COLOR_0 (linear RGB floats) and u32 indices,
//! in one buffer. An animated file ([`GlbAnimation`], `mdsurf surface --frames A:B -o
//! movie.glb`) holds one node per trajectory frame and one animation that shows one node at a
//! time by a STEP-interpolated `scale` (0 → 1 → 0), which Blender, three.js and glTF viewers
//! play; nodes other than the first have scale 0, so a viewer that ignores animations shows the
//! first frame.
//!
//! Key times (s): the selected frames play at `fps` frames per second, spaced by their simulation
//! times: `key_k = (t_k - t_0) / (fps * dt)` with `t_k` the frame times in ps and `dt` the median
//! time step between the selected frames (so gaps in the trajectory stay visible); frames without
//! increasing times get `k / fps`. See [`key_times`].
//!
//! The JSON is built with the `gltf-json` crate (typed, spec-checked structures); the GLB
//! container (12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros, all
//! 4-byte aligned) is written here. The frames of an animation are streamed into an anonymous
//! temporary file as they come (one mesh in memory at a time), and copied behind the JSON at the
//! end, atomically.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;
use gltf_json as json;
use json::accessor::{ComponentType as C, Type as T};
use json::validation::{Checked, USize64};

use super::{AtomicFile, ExportError, too_large};
use crate::surface::Mesh;

/// `glTF` in little-endian: the GLB magic.
pub const GLB_MAGIC: u32 = 0x4654_6C67;
/// Chunk type of the JSON chunk (`JSON`).
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type of the binary chunk (`BIN\0`).
pub const CHUNK_BIN: u32 = 0x004E_4942;
/// Default playback rate of an animated file, in trajectory frames per second.
pub const DEFAULT_FPS: f64 = 25.0;
/// The largest GLB file: its length field has 32 bits.
const GLB_MAX: u64 = u32::MAX as u64;

/// Writes `mesh` as a binary glTF 2.0 file. An empty mesh gives a valid file with an empty node.
pub fn write_glb(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let mut doc = Doc::new();
    let mut bin = Vec::with_capacity(mesh.vertex_count() * 36 + mesh.indices.len() * 4);
    let gmesh = doc.append_mesh(&mut bin, mesh, None)?;
    let node = doc.root.push(json::Node {
        mesh: gmesh,
        ..Default::default()
    });
    doc.set_scene(vec![node]);
    doc.write(w, &mut |w| w.write_all(&bin))
}

/// The glTF document being built and the length of its binary buffer so far.
struct Doc {
    root: json::Root,
    bin_len: u64,
}

impl Doc {
    /// An empty document with one buffer (its length set in [`Doc::write`]).
    fn new() -> Doc {
        let mut root = json::Root {
            asset: json::Asset {
                generator: Some(format!("mdsurf {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        };
        root.push(json::Buffer {
            byte_length: USize64(0),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        Doc { root, bin_len: 0 }
    }

    /// Makes `nodes` the default scene.
    fn set_scene(&mut self, nodes: Vec<json::Index<json::Node>>) {
        let scene = self.root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes,
        });
        self.root.scene = Some(scene);
    }

    /// Appends `bytes` to the buffer (through `bin`) as one view; every section is a multiple
    /// of 4 bytes, so views stay aligned.
    fn view(
        &mut self,
        bin: &mut dyn Write,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> io::Result<json::Index<json::buffer::View>> {
        bin.write_all(bytes)?;
        let offset = self.bin_len;
        self.bin_len += bytes.len() as u64;
        if self.bin_len > GLB_MAX - (1 << 20) {
            return Err(too_large("a GLB file (4 GiB)"));
        }
        Ok(self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Checked::Valid),
            extensions: None,
            extras: Default::default(),
        }))
    }

    /// An accessor of `count` elements of `ty` in `view`, with optional min/max.
    fn accessor(
        &mut self,
        view: json::Index<json::buffer::View>,
        count: usize,
        ty: T,
        component: C,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> json::Index<json::Accessor> {
        let (min, max) = match min_max {
            Some((lo, hi)) => (Some(json::Value::from(lo)), Some(json::Value::from(hi))),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Checked::Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            name: None,
            type_: Checked::Valid(ty),
            min,
            max,
            normalized: false,
            sparse: None,
        })
    }

    /// Writes `mesh`'s vertices, normals, colours and indices to `bin` and adds its views,
    /// accessors and glTF mesh; `None` for an empty mesh.
    fn append_mesh(
        &mut self,
        bin: &mut dyn Write,
        mesh: &Mesh,
        name: Option<String>,
    ) -> io::Result<Option<json::Index<json::Mesh>>> {
        if mesh.triangle_count() == 0 || mesh.vertex_count() == 0 {
            return Ok(None);
        }
        let n = mesh.vertex_count();
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let mut bytes = Vec::with_capacity(n * 12);
        use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};

        for p in &mesh.positions {
            push_f32s(&mut bytes, p.to_array());
        }
        let view = self.view(bin, &bytes, Some(ArrayBuffer))?;
        let pos = self.accessor(
            view,
            n,
            T::Vec3,
            C::F32,
            Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
        );

        bytes.clear();
        for i in 0..n {
            let v = mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
            // NORMAL must be unit length: fall back to +z where the gradient vanished.
            push_f32s(&mut bytes, v.try_normalize().unwrap_or(Vec3::Z).to_array());
        }
        let view = self.view(bin, &bytes, Some(ArrayBuffer))?;
        let nrm = self.accessor(view, n, T::Vec3, C::F32, None);

        bytes.clear();
        for i in 0..n {
            let c = mesh.colours.get(i).copied().unwrap_or([1.0; 3]);
            let c = c.map(|x| {
                if x.is_finite() {
                    x.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            });
            push_f32s(&mut bytes, c);
        }
        let view = self.view(bin, &bytes, Some(ArrayBuffer))?;
        let col = self.accessor(view, n, T::Vec3, C::F32, None);

        bytes.clear();
        for &i in &mesh.indices {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
        let view = self.view(bin, &bytes, Some(ElementArrayBuffer))?;
        let idx = self.accessor(view, mesh.indices.len(), T::Scalar, C::U32, None);

        let mut attributes = BTreeMap::new();
        attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), pos);
        attributes.insert(Checked::Valid(json::mesh::Semantic::Normals), nrm);
        attributes.insert(Checked::Valid(json::mesh::Semantic::Colors(0)), col);
        Ok(Some(self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name,
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
        })))
    }

    /// Writes the GLB container: header, JSON chunk, and the BIN chunk whose `bin_len` bytes
    /// `copy_bin` writes (nothing when the buffer is empty).
    fn write(
        mut self,
        w: &mut dyn Write,
        copy_bin: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
    ) -> io::Result<()> {
        if self.bin_len == 0 {
            // A buffer must not be empty: a document without geometry has none.
            self.root.buffers.clear();
        } else {
            self.root.buffers[0].byte_length = USize64(self.bin_len);
        }
        let mut json_bytes = json::serialize::to_vec(&self.root).map_err(io::Error::other)?;
        pad_to_4(&mut json_bytes, b' ');
        let bin_padded = self.bin_len.next_multiple_of(4);
        let mut total = 12 + 8 + json_bytes.len() as u64;
        if self.bin_len > 0 {
            total += 8 + bin_padded;
        }
        let total = u32::try_from(total).map_err(|_| too_large("a GLB file (4 GiB)"))?;

        w.write_all(&GLB_MAGIC.to_le_bytes())?;
        w.write_all(&2u32.to_le_bytes())?;
        w.write_all(&total.to_le_bytes())?;
        w.write_all(&(json_bytes.len() as u32).to_le_bytes())?;
        w.write_all(&CHUNK_JSON.to_le_bytes())?;
        w.write_all(&json_bytes)?;
        if self.bin_len > 0 {
            w.write_all(&(bin_padded as u32).to_le_bytes())?;
            w.write_all(&CHUNK_BIN.to_le_bytes())?;
            copy_bin(w)?;
            w.write_all(&vec![0u8; (bin_padded - self.bin_len) as usize])?;
        }
        Ok(())
    }
}

fn pad_to_4(v: &mut Vec<u8>, with: u8) {
    v.resize(v.len().next_multiple_of(4), with);
}

fn push_f32s<const N: usize>(b: &mut Vec<u8>, v: [f32; N]) {
    for x in v {
        b.extend_from_slice(&x.to_le_bytes());
    }
}

/// Animation key times in seconds for frames with simulation times `times_ps` (ps), played at
/// `fps` frames per second: `(t_k - t_0) / (fps * dt)` with `dt` the median step between
/// consecutive times, when every time is known, finite and strictly increasing; else `k / fps`.
pub fn key_times(times_ps: &[Option<f64>], fps: f64) -> Vec<f32> {
    let fps = if fps.is_finite() && fps > 0.0 {
        fps
    } else {
        DEFAULT_FPS
    };
    let known: Option<Vec<f64>> = times_ps
        .iter()
        .map(|t| t.filter(|t| t.is_finite()))
        .collect();
    let mut steps: Vec<f64> = match &known {
        Some(t) => t.windows(2).map(|w| w[1] - w[0]).collect(),
        None => Vec::new(),
    };
    if let Some(t) = known
        && !steps.is_empty()
        && steps.iter().all(|&d| d > 0.0)
    {
        steps.sort_by(f64::total_cmp);
        let dt = steps[steps.len() / 2];
        return t
            .iter()
            .map(|&tk| ((tk - t[0]) / (dt * fps)) as f32)
            .collect();
    }
    (0..times_ps.len())
        .map(|k| (k as f64 / fps) as f32)
        .collect()
}

/// An animated GLB being written: one node per frame, added in playback order with
/// [`GlbAnimation::add_frame`]; [`GlbAnimation::finish`] adds the animation and renames the
/// file into place. Dropping it unfinished leaves any existing file untouched.
pub struct GlbAnimation {
    target: PathBuf,
    doc: Doc,
    /// The buffer's bytes so far, in an anonymous temporary file.
    bin: BufWriter<File>,
    /// Per frame: its node, trajectory index and time (ps).
    frames: Vec<(json::Index<json::Node>, usize, Option<f64>)>,
    fps: f64,
}

impl GlbAnimation {
    /// Starts an animated GLB at `target`, played at `fps` trajectory frames per second.
    pub fn create(target: &Path, fps: f64) -> Result<GlbAnimation, ExportError> {
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let tmp = tempfile::tempfile_in(dir).map_err(|e| ExportError::io(target, e))?;
        Ok(GlbAnimation {
            target: target.to_path_buf(),
            doc: Doc::new(),
            bin: BufWriter::with_capacity(1 << 20, tmp),
            frames: Vec::new(),
            fps,
        })
    }

    /// Adds trajectory frame `index` (simulation time `time_ps`) with its `mesh`.
    pub fn add_frame(
        &mut self,
        index: usize,
        time_ps: Option<f64>,
        mesh: &Mesh,
    ) -> Result<(), ExportError> {
        let name = match time_ps {
            Some(t) => format!("frame {index} ({t} ps)"),
            None => format!("frame {index}"),
        };
        let gmesh = self
            .doc
            .append_mesh(&mut self.bin, mesh, Some(name.clone()))
            .map_err(|e| ExportError::io(&self.target, e))?;
        let node = self.doc.root.push(json::Node {
            mesh: gmesh,
            name: Some(name),
            // Only the first frame shows when the animation does not play.
            scale: (!self.frames.is_empty()).then_some([0.0; 3]),
            ..Default::default()
        });
        self.frames.push((node, index, time_ps));
        Ok(())
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames.len()
    }

    /// Adds the animation and writes the file atomically.
    pub fn finish(mut self) -> Result<(), ExportError> {
        let target = self.target.clone();
        let io_err = |e: io::Error| ExportError::io(&target, e);
        let times: Vec<Option<f64>> = self.frames.iter().map(|f| f.2).collect();
        let mut keys = key_times(&times, self.fps);
        let n = keys.len();
        if n > 1 {
            // The last frame shows for as long as the one before it.
            let last = keys[n - 1] + (keys[n - 1] - keys[n - 2]);
            keys.push(last);
            let mut channels = Vec::new();
            let mut samplers = Vec::new();
            for (k, &(node, _, _)) in self.frames.iter().enumerate() {
                // Hidden from the start, shown at its key, hidden at the next one.
                let mut track: Vec<(f32, f32)> = Vec::with_capacity(3);
                if k > 0 {
                    track.push((keys[0], 0.0));
                }
                track.push((keys[k], 1.0));
                track.push((keys[k + 1], if k + 1 < n { 0.0 } else { 1.0 }));
                let mut input = Vec::new();
                let mut output = Vec::new();
                for &(t, s) in &track {
                    push_f32s(&mut input, [t]);
                    push_f32s(&mut output, [s; 3]);
                }
                let view = self.doc.view(&mut self.bin, &input, None).map_err(io_err)?;
                let (lo, hi) = (track[0].0, track[track.len() - 1].0);
                let input = self.doc.accessor(
                    view,
                    track.len(),
                    T::Scalar,
                    C::F32,
                    Some((vec![lo], vec![hi])),
                );
                let view = self
                    .doc
                    .view(&mut self.bin, &output, None)
                    .map_err(io_err)?;
                let output = self.doc.accessor(view, track.len(), T::Vec3, C::F32, None);
                channels.push(json::animation::Channel {
                    sampler: json::Index::new(samplers.len() as u32),
                    target: json::animation::Target {
                        extensions: None,
                        extras: Default::default(),
                        node,
                        path: Checked::Valid(json::animation::Property::Scale),
                    },
                    extensions: None,
                    extras: Default::default(),
                });
                samplers.push(json::animation::Sampler {
                    extensions: None,
                    extras: Default::default(),
                    input,
                    interpolation: Checked::Valid(json::animation::Interpolation::Step),
                    output,
                });
            }
            self.doc.root.push(json::Animation {
                extensions: None,
                extras: Default::default(),
                channels,
                name: Some("trajectory".into()),
                samplers,
            });
        }
        let nodes = self.frames.iter().map(|f| f.0).collect();
        self.doc.set_scene(nodes);

        let mut tmp = self
            .bin
            .into_inner()
            .map_err(|e| ExportError::io(&target, e.into_error()))?;
        tmp.rewind().map_err(io_err)?;
        let mut out = AtomicFile::create(&target)?;
        self.doc
            .write(out.writer(), &mut |w| io::copy(&mut tmp, w).map(drop))
            .map_err(io_err)?;
        out.commit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_times_follow_simulation_times_at_the_frame_rate() {
        // Steps of 10 ps (median) at 10 frames/s: 0.1 s per 10 ps; the 20 ps gap stays.
        let t = [Some(5.0), Some(15.0), Some(25.0), Some(45.0)];
        let keys = key_times(&t, 10.0);
        let want = [0.0, 0.1, 0.2, 0.4];
        assert!(
            keys.iter().zip(want).all(|(k, w)| (k - w).abs() < 1e-6),
            "{keys:?}"
        );
        // Missing or non-increasing times: one frame per 1/fps s.
        assert_eq!(key_times(&[None, Some(1.0)], 4.0), [0.0, 0.25]);
        assert_eq!(key_times(&[Some(1.0), Some(1.0)], 4.0), [0.0, 0.25]);
        assert_eq!(key_times(&[Some(3.0)], 25.0), [0.0]);
    }

    #[test]
    fn an_empty_mesh_gives_a_file_without_buffer() {
        let mut out = Vec::new();
        write_glb(&mut out, &Mesh::default()).unwrap();
        assert_eq!(&out[..4], b"glTF");
        let text = String::from_utf8_lossy(&out);
        assert!(!text.contains("\"buffers\""), "{text}");
    }
}

//! The renderer: draws a [`GpuScene`] through a [`Camera`] with [`RenderSettings`] into
//! [`RenderTargets`]. [`Renderer::render`] is the one render-to-texture function; the window shows
//! its output texture, and screenshots, movies and tests read it back (see `readback`).

use glam::Mat4;

use super::camera::{Camera, Eye};
use super::pipelines::{CYLINDER_VERTICES, Pipelines};
use super::scene::{GpuScene, SurfaceLayer};
use super::screen_rect::{beyond_near_plane, covered_rect};

/// Surfaces at least this opaque are drawn in the opaque pass.
const OPAQUE: f32 = 0.999;
use super::settings::{RenderSettings, Stereo};
use super::targets::RenderTargets;
use super::view_uniform::ViewUniform;

/// Draws scenes on one wgpu device. Create once; reuse for every frame and image.
pub struct Renderer {
    pipelines: Pipelines,
    /// One uniform buffer per eye, so both eyes can be encoded before one submit.
    view_buffers: [wgpu::Buffer; 2],
    view_groups: [wgpu::BindGroup; 2],
    /// One uniform buffer per (eye, surface layer): each surface is drawn with its own
    /// opacity and colour. Grows with the number of layers; never shrinks.
    layer_views: std::sync::Mutex<Vec<(wgpu::Buffer, wgpu::BindGroup)>>,
}

/// One eye's pass: its view and projection matrices, the part of the output it covers, and
/// where it draws.
struct EyePass<'a> {
    matrices: (Mat4, Mat4),
    /// x, y, width, height in pixels.
    viewport: [u32; 4],
    target: &'a wgpu::TextureView,
    clear: bool,
}

impl Renderer {
    /// Builds the pipelines for `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        let pipelines = Pipelines::new(device);
        let make = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size_of::<ViewUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let view_buffers = [make("view uniform 0"), make("view uniform 1")];
        let group = |b: &wgpu::Buffer| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("view"),
                layout: &pipelines.view_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: b.as_entire_binding(),
                }],
            })
        };
        let view_groups = [group(&view_buffers[0]), group(&view_buffers[1])];
        Renderer {
            pipelines,
            view_buffers,
            view_groups,
            layer_views: std::sync::Mutex::new(Vec::new()),
        }
    }

    /// The uniform buffer and bind group of (eye, layer) slot `slot`, made when missing.
    fn layer_view(&self, device: &wgpu::Device, slot: usize) -> (wgpu::Buffer, wgpu::BindGroup) {
        let mut views = self
            .layer_views
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        while views.len() <= slot {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("surface layer view uniform"),
                size: size_of::<ViewUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("surface layer view"),
                layout: &self.pipelines.view_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
            views.push((buffer, group));
        }
        views[slot].clone()
    }

    /// Renders `scene` into `targets` (the output texture ends up in
    /// [`RenderTargets::colour_texture`]) and submits the work to `queue`.
    pub fn render(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        targets: &mut RenderTargets,
        scene: &GpuScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) {
        let [w, h] = targets.size();
        if settings.stereo.is_anaglyph() {
            targets.ensure_eyes(device);
        }
        let sep = settings.eye_separation;
        let focal = settings.focal_distance;
        let eye = |e: Eye, width: u32| {
            let aspect = width as f32 / h.max(1) as f32;
            camera.eye_matrices(e, sep, focal, aspect)
        };
        let passes: Vec<EyePass<'_>> = match (settings.stereo, &targets.eyes) {
            (Stereo::SideBySide | Stereo::SideBySideCross, _) => {
                let half = (w / 2).max(1);
                // Wall-eyed: left eye on the left; cross-eyed: swapped.
                let (first, second) = if settings.stereo == Stereo::SideBySide {
                    (Eye::Left, Eye::Right)
                } else {
                    (Eye::Right, Eye::Left)
                };
                vec![
                    EyePass {
                        matrices: eye(first, half),
                        viewport: [0, 0, half, h],
                        target: &targets.colour_view,
                        clear: true,
                    },
                    EyePass {
                        matrices: eye(second, w - half),
                        viewport: [half, 0, w - half, h],
                        target: &targets.colour_view,
                        clear: false,
                    },
                ]
            }
            (Stereo::Anaglyph | Stereo::AnaglyphGrey, Some([l, r])) => vec![
                EyePass {
                    matrices: eye(Eye::Left, w),
                    viewport: [0, 0, w, h],
                    target: l,
                    clear: true,
                },
                EyePass {
                    matrices: eye(Eye::Right, w),
                    viewport: [0, 0, w, h],
                    target: r,
                    clear: true,
                },
            ],
            _ => vec![EyePass {
                matrices: camera.matrices(w as f32 / h.max(1) as f32),
                viewport: [0, 0, w, h],
                target: &targets.colour_view,
                clear: true,
            }],
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("render"),
        });
        let layers = scene.surfaces.len();
        for (i, pass) in passes.iter().enumerate() {
            let u = ViewUniform::new(camera, pass.matrices, pass.viewport, settings);
            queue.write_buffer(&self.view_buffers[i], 0, bytemuck::bytes_of(&u));
            // Each surface layer's look (opacity, colour) in its own uniform.
            let layer_groups: Vec<wgpu::BindGroup> = scene
                .surfaces
                .iter()
                .enumerate()
                .map(|(k, layer)| {
                    let look = RenderSettings {
                        surface_opacity: layer.effective_opacity(settings),
                        surface_colour: layer.colour.or(settings.surface_colour),
                        ..*settings
                    };
                    let u = ViewUniform::new(camera, pass.matrices, pass.viewport, &look);
                    let (buffer, group) = self.layer_view(device, i * layers + k);
                    queue.write_buffer(&buffer, 0, bytemuck::bytes_of(&u));
                    group
                })
                .collect();
            self.encode_eye(
                device,
                &mut encoder,
                targets,
                scene,
                settings,
                pass,
                (&self.view_groups[i], &layer_groups),
            );
        }
        if let (true, Some([l, r])) = (settings.stereo.is_anaglyph(), &targets.eyes) {
            let group = self.post_group(device, l, r);
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("anaglyph"),
                color_attachments: &[Some(colour_attachment(&targets.colour_view, None))],
                ..Default::default()
            });
            rp.set_pipeline(if settings.stereo == Stereo::AnaglyphGrey {
                &self.pipelines.anaglyph_grey
            } else {
                &self.pipelines.anaglyph
            });
            rp.set_bind_group(0, &group, &[]);
            rp.draw(0..3, 0..1);
        }
        queue.submit([encoder.finish()]);
    }

    /// Adds the image `drawn` as progressive sample `k` (from 0) to the running mean in
    /// `mean` (`mean` = `drawn` for `k` = 0, else `mean` + (`drawn` - `mean`) / (`k` + 1)), then
    /// writes the mean into `shown` (an image of [`super::COLOUR_FORMAT`]). Submits and does not
    /// wait.
    pub(crate) fn add_sample(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        drawn: &wgpu::TextureView,
        (mean, shown): (&wgpu::TextureView, &wgpu::TextureView),
        k: u32,
    ) {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("progressive sample"),
        });
        for (source, target, pipeline, weight) in [
            (
                drawn,
                mean,
                &self.pipelines.mean_add,
                1.0 / f64::from(k + 1),
            ),
            (mean, shown, &self.pipelines.mean_show, 1.0),
        ] {
            let group = self.post_group(device, source, source);
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("progressive sample"),
                color_attachments: &[Some(colour_attachment(target, None))],
                ..Default::default()
            });
            rp.set_pipeline(pipeline);
            rp.set_blend_constant(wgpu::Color {
                r: weight,
                g: weight,
                b: weight,
                a: weight,
            });
            rp.set_bind_group(0, &group, &[]);
            rp.draw(0..3, 0..1);
        }
        queue.submit([encoder.finish()]);
    }

    fn post_group(
        &self,
        device: &wgpu::Device,
        a: &wgpu::TextureView,
        b: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("post"),
            layout: &self.pipelines.post_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(a),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(b),
                },
            ],
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn encode_eye(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        scene: &GpuScene,
        settings: &RenderSettings,
        pass: &EyePass<'_>,
        (view_group, layer_groups): (&wgpu::BindGroup, &[wgpu::BindGroup]),
    ) {
        let [x, y, w, h] = pass.viewport.map(|v| v as f32);
        let bg = settings.background.linear_rgb();
        let clear = pass.clear.then_some(wgpu::Color {
            r: bg[0] as f64,
            g: bg[1] as f64,
            b: bg[2] as f64,
            a: if settings.transparent_background {
                0.0
            } else {
                1.0
            },
        });
        // Surface layers split by their opacity: opaque ones in the opaque pass, see-through
        // ones in the order-independent transparency pass, invisible ones not at all.
        let drawn = |opaque: bool| -> Vec<usize> {
            (0..scene.surfaces.len())
                .filter(|&k| {
                    let layer = &scene.surfaces[k];
                    let a = layer.effective_opacity(settings);
                    settings.show_surface
                        && layer.has_surface()
                        && a > 0.0
                        && (a >= OPAQUE) == opaque
                })
                .collect()
        };
        let (opaque_layers, transparent_layers) = (drawn(true), drawn(false));
        // This eye's world-to-clip matrix, for where the surfaces' boxes lie on screen.
        let view_proj = pass.matrices.1 * pass.matrices.0;
        {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("opaque"),
                color_attachments: &[Some(colour_attachment(pass.target, clear))],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            rp.set_viewport(x, y, w, h, 0.0, 1.0);
            rp.set_bind_group(0, view_group, &[]);
            if let Some(s) = scene.spheres.as_ref().filter(|_| scene.sphere_count > 0) {
                rp.set_pipeline(&self.pipelines.sphere);
                rp.set_vertex_buffer(0, s.buffer.slice(..));
                rp.draw(0..6, 0..scene.sphere_count);
            }
            if let Some(c) = scene
                .cylinders
                .as_ref()
                .filter(|_| scene.cylinder_count > 0)
            {
                rp.set_pipeline(&self.pipelines.cylinder);
                rp.set_vertex_buffer(0, c.buffer.slice(..));
                rp.draw(0..CYLINDER_VERTICES, 0..scene.cylinder_count);
            }
            for &k in &opaque_layers {
                rp.set_bind_group(0, &layer_groups[k], &[]);
                // Back faces are drawn only where the near plane may cut the surface open.
                let layer = &scene.surfaces[k];
                let closed = layer.closed && beyond_near_plane(layer.bounds, view_proj);
                self.draw_mesh(&mut rp, layer, false, closed);
            }
        }
        // One full-screen pass over the drawn pixels of the opaque image that reads its depth:
        // the look pass (ambient occlusion, outlines and shadows) or the ambient occlusion alone.
        let post_pipeline = if settings.has_look_pass() {
            Some(self.pipelines.look.get(
                device,
                settings.ambient_occlusion > 0.0,
                settings.outline_width > 0.0,
                settings.shadows > 0.0,
            ))
        } else if settings.ambient_occlusion > 0.0 {
            Some(self.pipelines.ambient_occlusion.clone())
        } else {
            None
        };
        // Only where the scene can be on screen (2 px around it for rounding).
        let rect = covered_rect(scene.drawn_bounds(), view_proj, pass.viewport, 2.0);
        if let (Some(pipeline), Some([sx, sy, sw, sh])) = (post_pipeline, rect) {
            let depth_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("scene depth"),
                layout: &self.pipelines.depth_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&targets.depth_view),
                }],
            });
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth post pass"),
                color_attachments: &[Some(colour_attachment(pass.target, None))],
                // Read-only: the depth test picks the pixels while the shader reads it too.
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth_view,
                    depth_ops: None,
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            rp.set_viewport(x, y, w, h, 0.0, 1.0);
            rp.set_scissor_rect(sx, sy, sw, sh);
            rp.set_bind_group(0, view_group, &[]);
            rp.set_bind_group(1, &depth_group, &[]);
            rp.set_pipeline(&pipeline);
            rp.draw(0..3, 0..1);
        }
        if transparent_layers.is_empty() {
            return;
        }
        {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("transparent surface"),
                color_attachments: &[
                    Some(colour_attachment(
                        &targets.accum_view,
                        Some(wgpu::Color::TRANSPARENT),
                    )),
                    Some(colour_attachment(
                        &targets.reveal_view,
                        Some(wgpu::Color::WHITE),
                    )),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            rp.set_viewport(x, y, w, h, 0.0, 1.0);
            for &k in &transparent_layers {
                rp.set_bind_group(0, &layer_groups[k], &[]);
                self.draw_mesh(&mut rp, &scene.surfaces[k], true, false);
            }
        }
        let group = self.post_group(device, &targets.accum_view, &targets.reveal_view);
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("oit resolve"),
            color_attachments: &[Some(colour_attachment(pass.target, None))],
            ..Default::default()
        });
        rp.set_viewport(x, y, w, h, 0.0, 1.0);
        rp.set_pipeline(&self.pipelines.resolve);
        rp.set_bind_group(0, &group, &[]);
        rp.draw(0..3, 0..1);
    }

    /// Draws the surface: from the GPU engine's buffers with the indirect arguments it wrote,
    /// or from the uploaded mesh.
    /// Draws one surface; `seen_closed`: an opaque closed surface that the near plane does not
    /// cut, whose back faces are culled.
    fn draw_mesh(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        scene: &SurfaceLayer,
        transparent: bool,
        seen_closed: bool,
    ) {
        if let Some(g) = &scene.gpu_surface {
            rp.set_pipeline(match (transparent, seen_closed) {
                (true, _) => &self.pipelines.gpu_mesh_oit,
                (false, true) => &self.pipelines.gpu_mesh_culled,
                (false, false) => &self.pipelines.gpu_mesh_opaque,
            });
            rp.set_vertex_buffer(0, g.vertices.slice(..));
            rp.set_index_buffer(g.indices.slice(..), wgpu::IndexFormat::Uint32);
            rp.draw_indexed_indirect(&g.draw_args, 0);
            return;
        }
        rp.set_pipeline(match (transparent, seen_closed) {
            (true, _) => &self.pipelines.mesh_oit,
            (false, true) => &self.pipelines.mesh_culled,
            (false, false) => &self.pipelines.mesh_opaque,
        });
        let (Some(p), Some(n), Some(c), Some(i)) = (
            &scene.positions,
            &scene.normals,
            &scene.colours,
            &scene.indices,
        ) else {
            return;
        };
        rp.set_vertex_buffer(0, p.buffer.slice(..));
        rp.set_vertex_buffer(1, n.buffer.slice(..));
        rp.set_vertex_buffer(2, c.buffer.slice(..));
        rp.set_index_buffer(i.buffer.slice(..), wgpu::IndexFormat::Uint32);
        rp.draw_indexed(0..scene.index_count, 0, 0..1);
    }
}

fn colour_attachment(
    view: &wgpu::TextureView,
    clear: Option<wgpu::Color>,
) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
            store: wgpu::StoreOp::Store,
        },
    }
}

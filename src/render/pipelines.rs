//! The render pipelines, built once per device from shaders/render_scene.wgsl and
//! shaders/render_post.wgsl: opaque mesh, transparent mesh (weighted blended OIT), sphere
//! impostors, cylinders, the transparency resolve and the anaglyph composition; and from
//! shaders/render_ao.wgsl and shaders/render_look.wgsl the ambient occlusion and the look
//! (outlines, shadows) passes.

use super::scene::{CylinderInstance, SphereInstance};
use super::targets::{ACCUM_FORMAT, COLOUR_FORMAT, DEPTH_FORMAT, MEAN_FORMAT, REVEAL_FORMAT};

/// WGSL of the scene pass (after the shared view uniform, `shaders/render_view.wgsl`).
pub const SCENE_WGSL: &str = concat!(
    include_str!("../../shaders/render_view.wgsl"),
    include_str!("../../shaders/render_scene.wgsl")
);
/// WGSL of the full-screen passes.
pub const POST_WGSL: &str = include_str!("../../shaders/render_post.wgsl");
/// WGSL of the ambient occlusion pass (after the shared view uniform).
pub const AO_WGSL: &str = concat!(
    include_str!("../../shaders/render_view.wgsl"),
    include_str!("../../shaders/render_ao.wgsl")
);

/// WGSL of the look pass: ambient occlusion, outlines and shadows in one pass (after the shared
/// view uniform and the ambient occlusion's functions).
pub const LOOK_WGSL: &str = concat!(
    include_str!("../../shaders/render_view.wgsl"),
    include_str!("../../shaders/render_ao.wgsl"),
    include_str!("../../shaders/render_look.wgsl")
);

/// Every render shader as `(file name, full source)`, for validation.
pub const ALL: &[(&str, &str)] = &[
    ("render_scene.wgsl", SCENE_WGSL),
    ("render_post.wgsl", POST_WGSL),
    ("render_ao.wgsl", AO_WGSL),
    ("render_look.wgsl", LOOK_WGSL),
];

/// Segments around a cylinder (`CYLINDER_SEGMENTS` in `shaders/render_scene.wgsl`).
pub(crate) const CYLINDER_SEGMENTS: u32 = 12;
/// Vertices per cylinder instance (two triangles per segment; see `vs_cylinder`).
pub const CYLINDER_VERTICES: u32 = CYLINDER_SEGMENTS * 6;

pub(crate) struct Pipelines {
    pub view_layout: wgpu::BindGroupLayout,
    pub post_layout: wgpu::BindGroupLayout,
    pub depth_layout: wgpu::BindGroupLayout,
    pub ambient_occlusion: wgpu::RenderPipeline,
    /// Ambient occlusion, outlines and shadows (shaders/render_look.wgsl), made on first use.
    pub look: LookPipelines,
    pub mesh_opaque: wgpu::RenderPipeline,
    /// `mesh_opaque` with back faces culled, for a closed surface seen from outside.
    pub mesh_culled: wgpu::RenderPipeline,
    pub mesh_oit: wgpu::RenderPipeline,
    /// The opaque and transparent mesh pipelines for one interleaved vertex buffer
    /// ([`crate::gpu::GpuSurface::vertex_layout`]: the GPU engine's output).
    pub gpu_mesh_opaque: wgpu::RenderPipeline,
    /// `gpu_mesh_opaque` with back faces culled: for a closed surface seen from outside (the
    /// engines' meshes are counter-clockwise seen from outside), where every back face lies
    /// behind a front one.
    pub gpu_mesh_culled: wgpu::RenderPipeline,
    pub gpu_mesh_oit: wgpu::RenderPipeline,
    pub sphere: wgpu::RenderPipeline,
    pub cylinder: wgpu::RenderPipeline,
    pub resolve: wgpu::RenderPipeline,
    pub anaglyph: wgpu::RenderPipeline,
    /// The luminance (grey) anaglyph composition.
    pub anaglyph_grey: wgpu::RenderPipeline,
    /// Adds a sample's image to the running mean of progressive samples (weight: the blend
    /// constant).
    pub mean_add: wgpu::RenderPipeline,
    /// Writes the running mean into an output image.
    pub mean_show: wgpu::RenderPipeline,
}

/// The read-only depth state of a full-screen pass after the opaque scene that shades only the
/// drawn pixels. Its triangle lies on the far plane (depth 1) and the test against the scene's
/// depth buffer (read-only, also read by the shader) passes only where something was drawn
/// (depth below 1), so that a driver skips the empty background before the shader runs: a CPU
/// driver such as lavapipe runs a fragment shader's branches under a mask and would otherwise
/// pay for every empty pixel as for a drawn one.
fn drawn_pixels_depth() -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    })
}

/// The look pass's pipelines, one per combination of its parts (ambient occlusion, outlines,
/// shadows), each compiled with only its parts (WGSL override constants: a CPU
/// driver such as lavapipe runs every instruction of a shader whatever its uniforms say).
pub(crate) struct LookPipelines {
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    made: std::sync::Mutex<[Option<wgpu::RenderPipeline>; 8]>,
}

impl LookPipelines {
    /// The pipeline with the parts asked for, compiled on first use.
    pub fn get(
        &self,
        device: &wgpu::Device,
        ao: bool,
        outline: bool,
        shadows: bool,
    ) -> wgpu::RenderPipeline {
        let key = usize::from(ao) | usize::from(outline) << 1 | usize::from(shadows) << 2;
        let mut made = self
            .made
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(p) = &made[key] {
            return p.clone();
        }
        let _compiling = crate::gpu::context::compile_lock();
        // Outline colour over the shaded image: colour = src + dst * (1 - src alpha); the alpha
        // kept (the pass shades drawn pixels only, which stay opaque).
        let target = [colour_target(Some(wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        }))];
        let flag = |on: bool| if on { 1.0 } else { 0.0 };
        let constants = [
            ("LOOK_AO", flag(ao)),
            ("LOOK_OUTLINE", flag(outline)),
            ("LOOK_SHADOWS", flag(shadows)),
        ];
        let p = pipeline(
            device,
            PipelineSpec {
                label: "look",
                module: &self.module,
                layout: &self.layout,
                vs: "vs_fullscreen",
                fs: "fs_look",
                buffers: &[],
                depth: drawn_pixels_depth(),
                targets: &target,
                constants: &constants,
            },
        );
        made[key] = Some(p.clone());
        p
    }
}

fn vec3_buffer(location: u32) -> [wgpu::VertexAttribute; 1] {
    [wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: 0,
        shader_location: location,
    }]
}

fn vec3_layout(attributes: &[wgpu::VertexAttribute]) -> wgpu::VertexBufferLayout<'_> {
    wgpu::VertexBufferLayout {
        array_stride: 12,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes,
    }
}

const SPHERE_ATTRS: [wgpu::VertexAttribute; 2] =
    wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4];
const CYLINDER_ATTRS: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4];

fn depth(write: bool) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(wgpu::CompareFunction::LessEqual),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    })
}

fn colour_target(blend: Option<wgpu::BlendState>) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format: COLOUR_FORMAT,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

struct PipelineSpec<'a> {
    label: &'a str,
    module: &'a wgpu::ShaderModule,
    layout: &'a wgpu::PipelineLayout,
    vs: &'a str,
    fs: &'a str,
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    depth: Option<wgpu::DepthStencilState>,
    targets: &'a [Option<wgpu::ColorTargetState>],
    /// Values of the shader's pipeline-overridable constants.
    constants: &'a [(&'a str, f64)],
}

fn pipeline(device: &wgpu::Device, s: PipelineSpec<'_>) -> wgpu::RenderPipeline {
    pipeline_culling(device, s, None)
}

/// [`pipeline`] drawing only the triangles not facing `cull` (counter-clockwise is front).
fn pipeline_culling(
    device: &wgpu::Device,
    s: PipelineSpec<'_>,
    cull: Option<wgpu::Face>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(s.label),
        layout: Some(s.layout),
        vertex: wgpu::VertexState {
            module: s.module,
            entry_point: Some(s.vs),
            compilation_options: Default::default(),
            buffers: s.buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: cull,
            ..Default::default()
        },
        depth_stencil: s.depth,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: s.module,
            entry_point: Some(s.fs),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: s.constants,
                ..Default::default()
            },
            targets: s.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl Pipelines {
    pub fn new(device: &wgpu::Device) -> Self {
        // One renderer's shaders and pipelines compile under the engine's process-wide lock
        // (a driver deadlocked on concurrent compiles; see `compile_lock`).
        let _compiling = crate::gpu::context::compile_lock();
        let scene = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render_scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SCENE_WGSL.into()),
        });
        let post = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render_post.wgsl"),
            source: wgpu::ShaderSource::Wgsl(POST_WGSL.into()),
        });
        let view_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view uniform"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let tex = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let post_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("post textures"),
            entries: &[tex(0), tex(1)],
        });
        let ao = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render_ao.wgsl"),
            source: wgpu::ShaderSource::Wgsl(AO_WGSL.into()),
        });
        let look_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render_look.wgsl"),
            source: wgpu::ShaderSource::Wgsl(LOOK_WGSL.into()),
        });
        let depth_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ao depth"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let ao_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ambient occlusion"),
            bind_group_layouts: &[Some(&view_layout), Some(&depth_layout)],
            immediate_size: 0,
        });
        let scene_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&view_layout)],
            immediate_size: 0,
        });
        let post_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("post"),
            bind_group_layouts: &[Some(&post_layout)],
            immediate_size: 0,
        });

        let p = vec3_buffer(0);
        let n = vec3_buffer(1);
        let c = vec3_buffer(2);
        let mesh_buffers = [
            Some(vec3_layout(&p)),
            Some(vec3_layout(&n)),
            Some(vec3_layout(&c)),
        ];
        let gpu_mesh_buffers = [Some(crate::gpu::GpuSurface::vertex_layout())];
        let sphere_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: size_of::<SphereInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &SPHERE_ATTRS,
        })];
        let cylinder_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: size_of::<CylinderInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &CYLINDER_ATTRS,
        })];

        let opaque_target = [colour_target(None)];
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let reveal = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::OneMinusSrc,
            operation: wgpu::BlendOperation::Add,
        };
        let oit_targets = [
            Some(wgpu::ColorTargetState {
                format: ACCUM_FORMAT,
                blend: Some(wgpu::BlendState {
                    color: additive,
                    alpha: additive,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            }),
            Some(wgpu::ColorTargetState {
                format: REVEAL_FORMAT,
                blend: Some(wgpu::BlendState {
                    color: reveal,
                    alpha: reveal,
                }),
                write_mask: wgpu::ColorWrites::RED,
            }),
        ];
        let scene_spec = |label, vs, fs, buffers, depth, targets| PipelineSpec {
            label,
            module: &scene,
            layout: &scene_layout,
            vs,
            fs,
            buffers,
            depth,
            targets,
            constants: &[],
        };
        let mesh_opaque = pipeline(
            device,
            scene_spec(
                "mesh opaque",
                "vs_mesh",
                "fs_mesh",
                &mesh_buffers,
                depth(true),
                &opaque_target,
            ),
        );
        let mesh_culled = pipeline_culling(
            device,
            scene_spec(
                "mesh opaque, back faces culled",
                "vs_mesh",
                "fs_mesh",
                &mesh_buffers,
                depth(true),
                &opaque_target,
            ),
            Some(wgpu::Face::Back),
        );
        let mesh_oit = pipeline(
            device,
            scene_spec(
                "mesh oit",
                "vs_mesh",
                "fs_mesh_oit",
                &mesh_buffers,
                depth(false),
                &oit_targets,
            ),
        );
        let gpu_mesh_opaque = pipeline(
            device,
            scene_spec(
                "gpu mesh opaque",
                "vs_mesh",
                "fs_mesh",
                &gpu_mesh_buffers,
                depth(true),
                &opaque_target,
            ),
        );
        let gpu_mesh_culled = pipeline_culling(
            device,
            scene_spec(
                "gpu mesh opaque, back faces culled",
                "vs_mesh",
                "fs_mesh",
                &gpu_mesh_buffers,
                depth(true),
                &opaque_target,
            ),
            Some(wgpu::Face::Back),
        );
        let gpu_mesh_oit = pipeline(
            device,
            scene_spec(
                "gpu mesh oit",
                "vs_mesh",
                "fs_mesh_oit",
                &gpu_mesh_buffers,
                depth(false),
                &oit_targets,
            ),
        );
        let sphere = pipeline(
            device,
            scene_spec(
                "spheres",
                "vs_sphere",
                "fs_sphere",
                &sphere_buffers,
                depth(true),
                &opaque_target,
            ),
        );
        let cylinder = pipeline(
            device,
            scene_spec(
                "cylinders",
                "vs_cylinder",
                "fs_cylinder",
                &cylinder_buffers,
                depth(true),
                &opaque_target,
            ),
        );
        let over = [colour_target(Some(wgpu::BlendState::ALPHA_BLENDING))];
        let post_spec = |label, fs, targets| PipelineSpec {
            label,
            module: &post,
            layout: &post_pl,
            vs: "vs_fullscreen",
            fs,
            buffers: &[],
            depth: None,
            targets,
            constants: &[],
        };
        let resolve = pipeline(device, post_spec("oit resolve", "fs_oit_resolve", &over));
        let anaglyph = pipeline(device, post_spec("anaglyph", "fs_anaglyph", &opaque_target));
        let anaglyph_grey = pipeline(
            device,
            post_spec("grey anaglyph", "fs_anaglyph_grey", &opaque_target),
        );
        // The running mean of progressive samples: mean = w * sample + (1 - w) * mean, w the
        // blend constant (1 / samples so far), in linear colour at half-float precision.
        let weighted = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Constant,
            dst_factor: wgpu::BlendFactor::OneMinusConstant,
            operation: wgpu::BlendOperation::Add,
        };
        let mean_target = [Some(wgpu::ColorTargetState {
            format: MEAN_FORMAT,
            blend: Some(wgpu::BlendState {
                color: weighted,
                alpha: weighted,
            }),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let mean_add = pipeline(device, post_spec("mean add", "fs_copy", &mean_target));
        let mean_show = pipeline(device, post_spec("mean show", "fs_copy", &opaque_target));
        // Multiplies the image by the occlusion factor (colour = dst * src; alpha kept).
        let multiply = [colour_target(Some(wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::Src,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        }))];
        let ambient_occlusion = pipeline(
            device,
            PipelineSpec {
                label: "ambient occlusion",
                module: &ao,
                layout: &ao_pl,
                vs: "vs_fullscreen",
                fs: "fs_ambient_occlusion",
                buffers: &[],
                // The background's occlusion is 1: only drawn pixels change.
                depth: drawn_pixels_depth(),
                targets: &multiply,
                constants: &[],
            },
        );
        Pipelines {
            look: LookPipelines {
                module: look_module,
                layout: ao_pl,
                made: std::sync::Mutex::new(Default::default()),
            },
            view_layout,
            post_layout,
            depth_layout,
            ambient_occlusion,
            mesh_opaque,
            mesh_culled,
            mesh_oit,
            gpu_mesh_opaque,
            gpu_mesh_culled,
            gpu_mesh_oit,
            sphere,
            cylinder,
            resolve,
            anaglyph,
            anaglyph_grey,
            mean_add,
            mean_show,
        }
    }
}

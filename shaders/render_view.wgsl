// Shared by the render passes that read the view (render_scene, render_ao, render_look): the
// per-frame view
// uniform. src/render/pipelines.rs prepends this file to each of them, so it is written once.

// Twin of `ViewUniform` in src/render/renderer.rs (352 bytes).
struct View {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
    // xyz: unit direction towards the key light in view space.
    light_dir: vec4<f32>,
    // xyz: two unit vectors across `light_dir` and each other (the shadow rays' cone).
    light_across: vec4<f32>,
    light_up: vec4<f32>,
    // rgb: linear background colour (the depth cue fades towards it).
    background: vec4<f32>,
    // x: depth-cue start (Å from the eye), y: end (Å), z: strength 0..1, w: 1 = orthographic.
    fog: vec4<f32>,
    // x: surface opacity 0..1, y: 1 = use `surface_colour` instead of vertex colours.
    surface: vec4<f32>,
    // rgb: single surface colour (linear).
    surface_colour: vec4<f32>,
    // x: specular strength, y: near clip (Å), z: far clip (Å), w: unused.
    misc: vec4<f32>,
    // x: ambient occlusion strength, y: its reach (Å), z: viewport height (px), w: unused.
    ao: vec4<f32>,
    // The viewport in the render target: x, y, width, height (px).
    viewport: vec4<f32>,
    // A render-target pixel back to view space (see view_at in render_look.wgsl): xy scales
    // and zw offsets of pixel x and y towards view x and y at w = 1 (Å per pixel).
    unproject_px: vec4<f32>,
    // xy: the shift of view x and y per Å of view z, zw: the constant shift (Å).
    unproject_z: vec4<f32>,
    // x: outline width (px, 0 = off), y: shadow strength 0..1, z: shadow reach (Å), w: unused.
    look: vec4<f32>,
    // rgb: linear outline colour.
    outline_colour: vec4<f32>,
};

// Screen-space ambient occlusion of the renderer (src/render/renderer.rs), run after the opaque
// scene pass and before the transparent surface: each pixel compares its depth with 16 samples
// on a disc of about AO_RADIUS Å around it; neighbours in front of it (creases, pockets, atoms
// nestled in the surface) darken it. The output multiplies the image (blend: dst * src).

// View (twin of `ViewUniform` in src/render/renderer.rs) comes from render_view.wgsl,
// prepended by src/render/pipelines.rs.

@group(0) @binding(0) var<uniform> u: View;
@group(1) @binding(0) var depth_tex: texture_depth_2d;

struct FullscreenOut {
    @builtin(position) clip: vec4<f32>,
};

// One triangle that covers the viewport, on the far plane (depth 1): the pipelines' depth test
// against the scene's depth passes only the drawn pixels (`drawn_pixels_depth` in
// src/render/pipelines.rs).
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> FullscreenOut {
    let x = f32((vi << 1u) & 2u);
    let y = f32(vi & 2u);
    var o: FullscreenOut;
    o.clip = vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 1.0, 1.0);
    return o;
}

// Distance from the eye in Å for a depth-buffer value (0 near, 1 far).
fn eye_distance(d: f32) -> f32 {
    let n = u.misc.y;
    let f = u.misc.z;
    if (u.fog.w > 0.5) {
        return n + d * (f - n);
    }
    return n * f / (f - d * (f - n));
}

const SAMPLES: u32 = 16u;

// Occlusion factor 0..1 (1: open) at pixel `p` of depth `d0`; `noise` 0..1 turns the pattern.
// Also called by fs_look in render_look.wgsl, which appends to this file.
fn ambient_occlusion(p: vec2<i32>, d0: f32, noise: f32) -> f32 {
    let dims = vec2<i32>(textureDimensions(depth_tex));
    if (d0 >= 1.0) {
        return 1.0;
    }
    let z0 = eye_distance(d0);
    let reach = u.ao.y;
    // Reach in pixels: Å times pixels per Å at this depth.
    var px_per_a = u.proj[1][1] * 0.5 * u.ao.z;
    if (u.fog.w < 0.5) {
        px_per_a = px_per_a / max(z0, 1e-3);
    }
    let radius = clamp(reach * px_per_a, 2.0, 48.0);
    var occlusion = 0.0;
    for (var k = 0u; k < SAMPLES; k = k + 1u) {
        let t = (f32(k) + 0.5) / f32(SAMPLES);
        let angle = f32(k) * 2.3999632 + noise * 6.2831853;
        let offset = vec2<f32>(cos(angle), sin(angle)) * sqrt(t) * radius;
        let q = clamp(p + vec2<i32>(offset), vec2<i32>(0), dims - vec2<i32>(1));
        let dq = textureLoad(depth_tex, q, 0);
        if (dq >= 1.0) {
            continue;
        }
        let dz = z0 - eye_distance(dq);
        // In front by up to `reach`: occludes; much further in front: a separate object, fade out.
        let near = clamp(dz / reach, 0.0, 1.0);
        let range = 1.0 - smoothstep(reach, 3.0 * reach, dz);
        occlusion = occlusion + near * range;
    }
    return 1.0 - u.ao.x * clamp(occlusion / f32(SAMPLES) * 2.2, 0.0, 1.0);
}

// Interleaved gradient noise 0..1 of a pixel (rotates sample patterns per pixel), turned by
// the progressive sample's offset `u.misc.w` (0 for a plain draw).
fn pixel_noise(clip: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(0.06711056 * clip.x + 0.00583715 * clip.y) + u.misc.w);
}

@fragment
fn fs_ambient_occlusion(i: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let a = ambient_occlusion(p, textureLoad(depth_tex, p, 0), pixel_noise(i.clip.xy));
    return vec4<f32>(a, a, a, 1.0);
}

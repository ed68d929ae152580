// The figure look of the renderer (src/render/renderer.rs): one full-screen pass after the
// opaque scene and before the transparent surface, reading only the depth buffer, that does the
// ambient occlusion (render_ao.wgsl), and the parts below. It shades only the drawn pixels (its
// pipeline's depth test, `drawn_pixels_depth` in src/render/pipelines.rs) within the screen
// rectangle the scene covers (a scissor): the empty background is not shaded at all.
// The parts:
// - silhouette outlines: a drawn pixel is drawn in the outline colour where a neighbour
//   `look.x` pixels away is farther by a depth jump (relative to the depth) or empty, so the
//   line lies just inside each silhouette, on the nearer side of every depth edge, and where
//   the surface bends sharply (the slopes on both sides differ by more than about 60 degrees);
//   the inside of a smooth surface is left alone;
// - soft shadows from the key light (`light_dir`, the light that shade() in render_scene.wgsl
//   uses): a ray, turned per pixel within a cone of about 8 degrees, marches `look.z` Å from
//   each pixel towards the light through the depth buffer in jittered steps; a ray that passes
//   behind a nearer surface is blocked. Only what is on screen casts shadows.
// Output: premultiplied outline colour and a coverage alpha; blended with (one, 1 - src alpha)
// the image becomes dst * occlusion * shade * (1 - o) + colour * o. Drawn pixels stay opaque
// and the background is never written, so a transparent background keeps alpha 0.

// src/render/pipelines.rs prepends render_view.wgsl and render_ao.wgsl (the view uniform `u`,
// `depth_tex`, the full-screen triangle, eye_distance, ambient_occlusion, pixel_noise): this one
// pass also does the ambient occlusion when the look is on.

// The parts this pipeline draws (set per pipeline by src/render/pipelines.rs, so a CPU driver
// compiles only those; the uniforms' strengths still scale them).
override LOOK_AO: bool = true;
override LOOK_OUTLINE: bool = true;
override LOOK_SHADOWS: bool = true;

// Depth at pixel `q`, clamped into the viewport.
fn depth_at(q: vec2<i32>) -> f32 {
    let lo = vec2<i32>(u.viewport.xy);
    let hi = lo + vec2<i32>(u.viewport.zw) - vec2<i32>(1);
    return textureLoad(depth_tex, clamp(q, lo, hi), 0);
}

// View-space position (Å) of the pixel centre `px` (render-target pixels) at depth `d`.
fn view_position(px: vec2<f32>, d: f32) -> vec3<f32> {
    let uv = (px - u.viewport.xy) / u.viewport.zw;
    let h = u.inv_proj * vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, d, 1.0);
    return h.xyz / h.w;
}

// Size of one pixel in Å at distance `z` from the eye.
fn pixel_size(z: f32) -> f32 {
    let px_per_a = u.proj[1][1] * 0.5 * u.viewport.w;
    if (u.fog.w > 0.5) {
        return 1.0 / px_per_a;
    }
    return z / px_per_a;
}

// Depths of the four neighbours `k` pixels away: -x, +x, -y, +y.
struct Cross {
    k: i32,
    d: vec4<f32>,
};

fn cross_at(p: vec2<i32>, k: i32) -> Cross {
    var c: Cross;
    c.k = k;
    c.d = vec4<f32>(
        depth_at(p - vec2<i32>(k, 0)),
        depth_at(p + vec2<i32>(k, 0)),
        depth_at(p - vec2<i32>(0, k)),
        depth_at(p + vec2<i32>(0, k)),
    );
    return c;
}

// Crease strength 0..1 of the depths `zm`, `z0`, `zp` (Å) `span` Å apart: the slopes on the two
// sides differ by more than about 60 degrees.
fn crease(zm: f32, z0: f32, zp: f32, span: f32, jump: f32) -> f32 {
    if (abs(zm - z0) >= jump || abs(zp - z0) >= jump) {
        return 0.0;
    }
    // Cosine of the angle between the steps before and after (no atan: cheaper on CPUs).
    let a = vec2<f32>(span, z0 - zm);
    let b = vec2<f32>(span, zp - z0);
    let cos_bend = dot(a, b) * inverseSqrt(dot(a, a) * dot(b, b));
    return 1.0 - smoothstep(0.17, 0.54, cos_bend);
}

// Outline coverage 0..1 at a drawn pixel of depth `d0` (below 1: the drawn pipeline's depth
// test passes no other) with neighbours `c` at the outline width.
fn outline(d0: f32, c: Cross) -> f32 {
    if (u.look.x <= 0.0) {
        return 0.0;
    }
    let z0 = eye_distance(d0);
    let pix = pixel_size(z0);
    // A jump is more than 1.5 % of the depth plus a slope of 3 over the offset.
    let jump = 0.015 * z0 + 3.0 * f32(c.k) * pix;
    let far = vec4<f32>(1e30);
    let z = select(
        vec4<f32>(eye_distance(c.d.x), eye_distance(c.d.y), eye_distance(c.d.z),
                  eye_distance(c.d.w)),
        far,
        c.d >= vec4<f32>(1.0),
    );
    // A farther neighbour across a jump, or the background: this pixel is on its silhouette.
    let farthest = max(max(z.x, z.y), max(z.z, z.w));
    var o = smoothstep(jump, 2.0 * jump, farthest - z0);
    let span = f32(c.k) * pix;
    o = max(o, crease(z.x, z0, z.y, span, jump));
    return max(o, crease(z.z, z0, z.w, span, jump));
}

// Steps along the shadow ray.
const SHADOW_STEPS: u32 = 4u;

// Fraction 0..1 of the light blocked at pixel `p` of depth `d0` with neighbours `c`: the share
// of the key light blocked, times the key light's share of the pixel's light. Written without
// branches or early exits: a CPU driver runs a fragment shader's lanes together, and divergent
// loops with texture loads cost it far more than the arithmetic saved.
fn shadow(p: vec2<i32>, d0: f32, c: Cross, noise: f32) -> f32 {
    let centre = vec2<f32>(p) + 0.5;
    let pos = view_position(centre, min(d0, 0.999999));
    // Normal from the depth buffer: on each axis the side with the smaller depth step (chosen
    // on the stored depths, so only two neighbours are turned into positions).
    let k = f32(c.k);
    let left = abs(d0 - c.d.x) < abs(c.d.y - d0);
    let up = abs(d0 - c.d.z) < abs(c.d.w - d0);
    let sx = select(k, -k, left);
    let sy = select(k, -k, up);
    let px = view_position(centre + vec2<f32>(sx, 0.0), select(c.d.y, c.d.x, left));
    let py = view_position(centre + vec2<f32>(0.0, sy), select(c.d.w, c.d.z, up));
    let dx = (px - pos) * sign(sx);
    let dy = (py - pos) * sign(sy);
    // Pixel rows grow downwards, view-space y upwards: dy x dx points towards the eye.
    let n = normalize(cross(dy, dx) + vec3<f32>(0.0, 0.0, 1e-12));
    let l = normalize(u.light_dir.xyz);
    let ndotl = max(dot(n, l), 0.0);
    let pix = pixel_size(-pos.z);
    let start = pos + n * (2.0 * pix + 0.05);
    // The ray leans off the light by up to about 8 degrees, per pixel (a soft penumbra).
    let helper = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(l.x) > 0.9);
    let a = normalize(cross(l, helper));
    let b = cross(l, a);
    let jitter = vec2<f32>(noise, fract(noise * 1.618034)) * 2.0 - 1.0;
    let dir = normalize(l + 0.1 * (jitter.x * a + jitter.y * b));
    let reach = u.look.z;
    let thickness = 0.5 * reach;
    let bias = 0.1 + pix;
    var hit = 0.0;
    for (var s = 0u; s < SHADOW_STEPS; s = s + 1u) {
        let t = (f32(s) + fract(noise * 2.618034)) / f32(SHADOW_STEPS);
        // Denser steps near the surface, where the contact shadows are.
        let q = start + dir * (t * t * reach + pix);
        let clip = u.proj * vec4<f32>(q, 1.0);
        let uv = vec2<f32>(0.5, -0.5) * clip.xy / clip.w + 0.5;
        let inside = all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0));
        let qp = clamp(u.viewport.xy + uv * u.viewport.zw, u.viewport.xy,
                       u.viewport.xy + u.viewport.zw - 1.0);
        let dq = textureLoad(depth_tex, vec2<i32>(qp), 0);
        // How far the drawn surface lies in front of the ray point (Å); background: never.
        let behind = select(-q.z - eye_distance(dq), -1.0, dq >= 1.0 || !inside);
        hit = max(hit, smoothstep(bias, 2.0 * bias, behind)
            * (1.0 - smoothstep(0.5 * thickness, thickness, behind)));
    }
    // The key light's share of the light here (shade() in render_scene.wgsl: key 0.75 n.l over
    // about 0.3 of fill and ambient).
    let key = 0.75 * ndotl;
    return select(hit * key / (key + 0.3), 0.0, d0 >= 1.0);
}

@fragment
fn fs_look(i: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let d0 = textureLoad(depth_tex, p, 0);
    let noise = pixel_noise(i.clip.xy);
    var lit = 1.0;
    if (LOOK_AO) {
        lit = ambient_occlusion(p, d0, noise);
    }
    var o = 0.0;
    if (LOOK_OUTLINE || LOOK_SHADOWS) {
        // One set of neighbours for the outline and the shadow's normal.
        let c = cross_at(p, max(i32(round(u.look.x)), 1));
        if (LOOK_OUTLINE) {
            o = outline(d0, c);
        }
        if (LOOK_SHADOWS) {
            lit = lit * (1.0 - u.look.y * shadow(p, d0, c, noise));
        }
    }
    return vec4<f32>(u.outline_colour.rgb * o, 1.0 - lit * (1.0 - o));
}

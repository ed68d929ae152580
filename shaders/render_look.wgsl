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
//   behind a nearer surface is blocked. Only what is on screen casts shadows. The four pixels
//   of each 2x2 quad march one step each and share the result (`quad_max`).
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

// View-space position (Å) of the pixel centre `px` (render-target pixels) at distance `z` (Å)
// from the eye: `proj` solved for x and y through the coefficients of `u.unproject_px` and
// `u.unproject_z` (no divisions: a CPU driver divides far slower than it multiplies).
fn view_at(px: vec2<f32>, z: f32) -> vec3<f32> {
    let zv = -z;
    let w = u.proj[2].w * zv + u.proj[3].w;
    let xy = (px * u.unproject_px.xy + u.unproject_px.zw) * w - u.unproject_z.xy * zv
        - u.unproject_z.zw;
    return vec3<f32>(xy, zv);
}

// Size of one pixel in Å at distance `z` from the eye (the same at every distance when
// orthographic).
fn pixel_size(z: f32) -> f32 {
    return abs(u.unproject_px.y) * select(z, 1.0, u.fog.w > 0.5);
}

// smoothstep(e0, e0 + 1 / inv_width, x) with the width's inverse given (no division).
fn ramp(x: f32, e0: f32, inv_width: f32) -> f32 {
    let t = clamp((x - e0) * inv_width, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// The four neighbours `k` pixels away (-x, +x, -y, +y): their depths, and their distances from
// the eye (Å; the background at `FAR_AWAY`).
struct Cross {
    k: i32,
    d: vec4<f32>,
    z: vec4<f32>,
};

// Distance from the eye given to the background's pixels (Å).
const FAR_AWAY: f32 = 1e30;

fn cross_at(p: vec2<i32>, k: i32) -> Cross {
    var c: Cross;
    c.k = k;
    c.d = vec4<f32>(
        depth_at(p - vec2<i32>(k, 0)),
        depth_at(p + vec2<i32>(k, 0)),
        depth_at(p - vec2<i32>(0, k)),
        depth_at(p + vec2<i32>(0, k)),
    );
    c.z = select(
        vec4<f32>(eye_distance(c.d.x), eye_distance(c.d.y), eye_distance(c.d.z),
                  eye_distance(c.d.w)),
        vec4<f32>(FAR_AWAY),
        c.d >= vec4<f32>(1.0),
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
    return 1.0 - ramp(cos_bend, 0.17, 1.0 / (0.54 - 0.17));
}

// Outline coverage 0..1 at a drawn pixel at `z0` Å from the eye (the drawn pipeline's depth
// test passes no empty pixel) with neighbours `c` at the outline width.
fn outline(z0: f32, c: Cross) -> f32 {
    if (u.look.x <= 0.0) {
        return 0.0;
    }
    let pix = pixel_size(z0);
    // A jump is more than 1.5 % of the depth plus a slope of 3 over the offset.
    let jump = 0.015 * z0 + 3.0 * f32(c.k) * pix;
    let z = c.z;
    // A farther neighbour across a jump, or the background: this pixel is on its silhouette.
    let farthest = max(max(z.x, z.y), max(z.z, z.w));
    var o = smoothstep(jump, 2.0 * jump, farthest - z0);
    let span = f32(c.k) * pix;
    o = max(o, crease(z.x, z0, z.y, span, jump));
    return max(o, crease(z.z, z0, z.w, span, jump));
}

// Steps along the shadow ray, shared by the four pixels of a 2x2 quad: each pixel marches one
// of them (its place in the quad picks which) and the quad takes the largest blocking of the
// four (`quad_max`), so a pixel pays one depth load for a march of four.
const SHADOW_STEPS: u32 = 4u;

// Largest of `v` over the pixel's 2x2 quad, through fine derivatives (the differences between
// the quad's columns and rows). Called in uniform control flow: the quad's pixels outside the
// drawn area run as helpers and give their `v` too, so callers pass 0 there.
fn quad_max(v: f32, corner: vec2<i32>) -> f32 {
    // The other column's and the other row's values: +difference from the left / top pixel,
    // -difference from the right / bottom one.
    let sx = select(1.0, -1.0, corner.x == 1);
    let sy = select(1.0, -1.0, corner.y == 1);
    let across = v + sx * dpdxFine(v);
    let below = v + sy * dpdyFine(v);
    let diagonal = across + sy * dpdyFine(across);
    return max(max(v, across), max(below, diagonal));
}

// The key light's share of the light at a drawn pixel of depth `d0`, `z` Å from the eye, and
// how much of it the pixel's step of the shadow march finds blocked (0..1; 0 on the
// background): `vec2(blocked, key share)`.
// Written without branches or early exits: a CPU driver runs a fragment shader's lanes
// together, and divergent loops with texture loads cost it far more than the arithmetic saved.
fn shadow_step(p: vec2<i32>, d0: f32, z: f32, c: Cross, noise: f32, step: u32) -> vec2<f32> {
    let centre = vec2<f32>(p) + 0.5;
    // Distances from the eye, the background's clamped to the far plane.
    let far = u.misc.z;
    let z0 = min(z, far);
    let pos = view_at(centre, z0);
    // Normal from the depth buffer: on each axis the side with the smaller depth step.
    let k = f32(c.k);
    let left = abs(z0 - c.z.x) < abs(c.z.y - z0);
    let up = abs(z0 - c.z.z) < abs(c.z.w - z0);
    let sx = select(k, -k, left);
    let sy = select(k, -k, up);
    let px = view_at(centre + vec2<f32>(sx, 0.0), min(select(c.z.y, c.z.x, left), far));
    let py = view_at(centre + vec2<f32>(0.0, sy), min(select(c.z.w, c.z.z, up), far));
    // Pixel rows grow downwards, view-space y upwards: (py - pos) x (px - pos) points towards
    // the eye when both steps go the positive way; each step taken the other way flips it.
    let flip = sign(sx) * sign(sy);
    let n = normalize(cross(py - pos, px - pos) * flip + vec3<f32>(0.0, 0.0, 1e-12));
    let l = u.light_dir.xyz;
    let ndotl = max(dot(n, l), 0.0);
    let pix = pixel_size(-pos.z);
    let start = pos + n * (2.0 * pix + 0.05);
    // The ray leans off the light by up to about 8 degrees, per pixel (a soft penumbra).
    let jitter = vec2<f32>(noise, fract(noise * 1.618034)) * 2.0 - 1.0;
    // (Not normalised: at most 1 % longer than the light's unit vector.)
    let dir = l + 0.1 * (jitter.x * u.light_across.xyz + jitter.y * u.light_up.xyz);
    let reach = u.look.z;
    let thickness = 0.5 * reach;
    let bias = 0.1 + pix;
    let t = (f32(step) + fract(noise * 2.618034)) / f32(SHADOW_STEPS);
    // Denser steps near the surface, where the contact shadows are.
    let q = start + dir * (t * t * reach + pix);
    // `proj * (q, 1)` with only the terms the projection has (see view_at).
    let clip_xy = vec2<f32>(u.proj[0].x * q.x, u.proj[1].y * q.y) + u.proj[2].xy * q.z
        + u.proj[3].xy;
    let clip_w = u.proj[2].w * q.z + u.proj[3].w;
    let uv = vec2<f32>(0.5, -0.5) * clip_xy * (1.0 / clip_w) + 0.5;
    let inside = all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0));
    let qp = clamp(u.viewport.xy + uv * u.viewport.zw, u.viewport.xy,
                   u.viewport.xy + u.viewport.zw - 1.0);
    let dq = textureLoad(depth_tex, vec2<i32>(qp), 0);
    // How far the drawn surface lies in front of the ray point (Å); background: never.
    let behind = select(-q.z - eye_distance(dq), -1.0, dq >= 1.0 || !inside);
    let hit = ramp(behind, bias, 1.0 / bias)
        * (1.0 - ramp(behind, 0.5 * thickness, 2.0 / thickness));
    // The key light's share of the light here (shade() in render_scene.wgsl: key 0.75 n.l over
    // about 0.3 of fill and ambient).
    let key = 0.75 * ndotl;
    return select(vec2<f32>(hit, key / (key + 0.3)), vec2<f32>(0.0), d0 >= 1.0);
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
        // The pixel's distance from the eye (Å), for both.
        let z0 = eye_distance(d0);
        if (LOOK_OUTLINE) {
            o = outline(z0, c);
        }
        if (LOOK_SHADOWS) {
            // This pixel's step of the quad's march (its place in the 2x2 quad).
            let corner = p & vec2<i32>(1);
            let step = u32(corner.x + 2 * corner.y);
            let s = shadow_step(p, d0, z0, c, noise, step);
            lit = lit * (1.0 - u.look.y * quad_max(s.x, corner) * s.y);
        }
    }
    return vec4<f32>(u.outline_colour.rgb * o, 1.0 - lit * (1.0 - o));
}

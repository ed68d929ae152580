// The figure look of the renderer (src/render/renderer.rs), one full-screen pass after the
// ambient occlusion and before the transparent surface, reading only the depth buffer:
// - silhouette outlines: a pixel is drawn in the outline colour where a neighbour `look.x`
//   pixels away is nearer by a depth jump (relative to the depth), so the line lies just outside
//   each silhouette, and where the surface bends sharply (the slopes on both sides differ by more
//   than about 60 degrees); the inside of a smooth surface is left alone;
// - soft shadows from the key light (`light_dir`, the light that shade() in render_scene.wgsl
//   uses): a few jittered rays march `look.z` Å from each pixel towards the light through the
//   depth buffer; a ray that passes behind a nearer surface is blocked. Only what is on screen
//   casts shadows.
// Output: premultiplied outline colour and a coverage alpha; blended with (one, 1 - src alpha)
// the image becomes dst * shade * (1 - o) + colour * o, and the alpha of a background pixel
// under an outline becomes o (transparent backgrounds).

// View (twin of `ViewUniform` in src/render/renderer.rs) comes from render_view.wgsl,
// prepended by src/render/pipelines.rs.

@group(0) @binding(0) var<uniform> u: View;
@group(1) @binding(0) var depth_tex: texture_depth_2d;

struct FullscreenOut {
    @builtin(position) clip: vec4<f32>,
};

// One triangle that covers the viewport.
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> FullscreenOut {
    let x = f32((vi << 1u) & 2u);
    let y = f32(vi & 2u);
    var o: FullscreenOut;
    o.clip = vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
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

// Outline coverage 0..1 at pixel `p` of depth `d0`.
fn outline(p: vec2<i32>, d0: f32) -> f32 {
    let r = u.look.x;
    if (r <= 0.0) {
        return 0.0;
    }
    let background = d0 >= 1.0;
    let z0 = eye_distance(d0);
    let pix = pixel_size(z0);
    // A jump is more than 1.5 % of the depth plus a slope of 3 over the offset.
    let jump = 0.015 * z0 + 3.0 * r * pix;
    var o = 0.0;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let angle = f32(k) * 0.7853982;
        let dir = vec2<f32>(cos(angle), sin(angle));
        let off = vec2<i32>(round(dir * max(r, 1.0)));
        let dm = depth_at(p - off);
        let dp = depth_at(p + off);
        if (background) {
            // Background next to anything drawn: the silhouette.
            o = max(o, select(0.0, 1.0, min(dm, dp) < 1.0));
            continue;
        }
        let zm = select(eye_distance(dm), 1e30, dm >= 1.0);
        let zp = select(eye_distance(dp), 1e30, dp >= 1.0);
        // A nearer neighbour across a jump: this pixel is just behind its silhouette.
        o = max(o, smoothstep(jump, 2.0 * jump, z0 - min(zm, zp)));
        if (abs(zm - z0) < jump && abs(zp - z0) < jump) {
            // A crease: the slopes on the two sides differ by more than about 60 degrees.
            let span = length(vec2<f32>(off)) * pix;
            let bend = abs(atan((zp - z0) / span) - atan((z0 - zm) / span));
            o = max(o, smoothstep(1.0, 1.4, bend));
        }
    }
    return o;
}

// Rays per pixel and steps per ray of the shadow test.
const SHADOW_RAYS: u32 = 3u;
const SHADOW_STEPS: u32 = 6u;

// Fraction 0..1 of the key light blocked at pixel `p` of depth `d0`, times how much of the
// pixel's light the key light gives.
fn shadow(p: vec2<i32>, d0: f32, noise: f32) -> f32 {
    if (u.look.y <= 0.0 || d0 >= 1.0) {
        return 0.0;
    }
    let c = vec2<f32>(p) + 0.5;
    let pos = view_position(c, d0);
    // Normal from the depth buffer: on each axis the side with the smaller step.
    let xl = view_position(c - vec2<f32>(1.0, 0.0), depth_at(p - vec2<i32>(1, 0)));
    let xr = view_position(c + vec2<f32>(1.0, 0.0), depth_at(p + vec2<i32>(1, 0)));
    let yu = view_position(c - vec2<f32>(0.0, 1.0), depth_at(p - vec2<i32>(0, 1)));
    let yd = view_position(c + vec2<f32>(0.0, 1.0), depth_at(p + vec2<i32>(0, 1)));
    let dx = select(xr - pos, pos - xl, abs(pos.z - xl.z) < abs(xr.z - pos.z));
    let dy = select(yd - pos, pos - yu, abs(pos.z - yu.z) < abs(yd.z - pos.z));
    // Pixel rows grow downwards, view-space y upwards: dy x dx points towards the eye.
    let n = normalize(cross(dy, dx));
    let l = normalize(u.light_dir.xyz);
    let ndotl = dot(n, l);
    if (ndotl <= 0.0) {
        return 0.0;
    }
    let pix = pixel_size(-pos.z);
    let start = pos + n * (2.0 * pix + 0.05);
    // Two directions across the light for a cone of about 8 degrees (a soft penumbra).
    let a = normalize(cross(l, select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0),
                                       abs(l.x) > 0.9)));
    let b = cross(l, a);
    let reach = u.look.z;
    let thickness = 0.5 * reach;
    var blocked = 0.0;
    for (var k = 0u; k < SHADOW_RAYS; k = k + 1u) {
        let phi = (f32(k) + noise) * 6.2831853 / f32(SHADOW_RAYS);
        let dir = normalize(l + 0.14 * (cos(phi) * a + sin(phi) * b));
        var hit = 0.0;
        for (var s = 0u; s < SHADOW_STEPS; s = s + 1u) {
            let t = (f32(s) + fract(noise + f32(k) * 0.618034)) / f32(SHADOW_STEPS);
            // Denser steps near the surface, where the contact shadows are.
            let q = start + dir * (t * t * reach + pix);
            let clip = u.proj * vec4<f32>(q, 1.0);
            let ndc = clip.xy / clip.w;
            let qp = u.viewport.xy + vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * u.viewport.zw;
            if (any(qp < u.viewport.xy) || any(qp >= u.viewport.xy + u.viewport.zw)) {
                break;
            }
            let dq = textureLoad(depth_tex, vec2<i32>(qp), 0);
            if (dq >= 1.0) {
                continue;
            }
            // How far the drawn surface lies in front of the ray point (Å).
            let behind = -q.z - eye_distance(dq);
            let bias = 0.1 + pix;
            hit = max(hit, smoothstep(bias, 2.0 * bias, behind)
                * (1.0 - smoothstep(0.5 * thickness, thickness, behind)));
        }
        blocked = blocked + hit;
    }
    // The key light's share of the light here (shade() in render_scene.wgsl: key 0.75 n.l over
    // about 0.3 of fill and ambient).
    let key = 0.75 * ndotl;
    return blocked / f32(SHADOW_RAYS) * key / (key + 0.3);
}

@fragment
fn fs_look(i: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let d0 = textureLoad(depth_tex, p, 0);
    // Interleaved gradient noise turns the shadow rays per pixel.
    let noise = fract(52.9829189 * fract(0.06711056 * i.clip.x + 0.00583715 * i.clip.y));
    let o = outline(p, d0);
    let lit = 1.0 - u.look.y * shadow(p, d0, noise);
    return vec4<f32>(u.outline_colour.rgb * o, 1.0 - lit * (1.0 - o));
}

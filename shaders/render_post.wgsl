// Full-screen passes of the renderer (src/render/renderer.rs) that run after the scene pass:
// resolving the weighted blended transparency targets over the opaque image, and composing two
// eye images into a red/cyan anaglyph (colour, or grey from each eye's luminance).
// Also the copy progressive samples average with.

struct FullscreenOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

// One triangle that covers the viewport.
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> FullscreenOut {
    let x = f32((vi << 1u) & 2u);
    let y = f32(vi & 2u);
    var o: FullscreenOut;
    o.clip = vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
    o.uv = vec2<f32>(x, y);
    return o;
}

@group(0) @binding(0) var tex_a: texture_2d<f32>;
@group(0) @binding(1) var tex_b: texture_2d<f32>;

// tex_a: accumulated premultiplied colour and weight; tex_b.r: product of (1 - alpha).
// Output is blended with (src alpha, 1 - src alpha) over the opaque image.
@fragment
fn fs_oit_resolve(i: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let accum = textureLoad(tex_a, p, 0);
    let reveal = textureLoad(tex_b, p, 0).r;
    if (reveal >= 0.9999) {
        discard;
    }
    let avg = accum.rgb / max(accum.a, 1e-5);
    return vec4<f32>(avg, 1.0 - reveal);
}

// Luminance of a linear colour (Rec. 709 weights, the same in the tests of
// tests/it/render_stereo.rs).
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// tex_a: left eye, tex_b: right eye (both linear colour). Colour anaglyph: red from the left
// eye's red channel, green and blue from the right eye's.
@fragment
fn fs_anaglyph(i: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let l = textureLoad(tex_a, p, 0).rgb;
    let r = textureLoad(tex_b, p, 0).rgb;
    return vec4<f32>(l.r, r.g, r.b, 1.0);
}

// Grey anaglyph: each eye is turned into luminance first (red: the left eye's, green and blue:
// the right eye's), so coloured surfaces do not rival between the eyes.
@fragment
fn fs_anaglyph_grey(i: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(i.clip.xy);
    let l = luminance(textureLoad(tex_a, p, 0).rgb);
    let r = luminance(textureLoad(tex_b, p, 0).rgb);
    return vec4<f32>(l, r, r, 1.0);
}

// tex_a: a colour image, copied as it is. Progressive samples (src/render/progressive.rs) draw
// each sample's image into their running mean with this (blended by a constant weight), and
// the mean into the shown image.
@fragment
fn fs_copy(i: FullscreenOut) -> @location(0) vec4<f32> {
    return textureLoad(tex_a, vec2<i32>(i.clip.xy), 0);
}

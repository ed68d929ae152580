// Scene pass of the renderer (src/render/renderer.rs): the surface mesh (opaque, or into the
// weighted blended OIT targets when semi-transparent), atoms as ray-cast sphere impostors and
// bonds as instanced cylinders. All shading happens in view space, in linear colour.

// View (twin of `ViewUniform` in src/render/renderer.rs) comes from render_view.wgsl,
// prepended by src/render/pipelines.rs.

@group(0) @binding(0) var<uniform> u: View;

// Lighting: a key light, a dim fill from below-right, hemispheric ambient, Blinn-Phong highlights,
// then a linear depth cue that fades far geometry towards the background.
fn shade(base: vec3<f32>, n_in: vec3<f32>, pos_view: vec3<f32>) -> vec3<f32> {
    var n = normalize(n_in);
    var v: vec3<f32>;
    if (u.fog.w > 0.5) {
        v = vec3<f32>(0.0, 0.0, 1.0);
    } else {
        v = normalize(-pos_view);
    }
    let l = normalize(u.light_dir.xyz);
    let fill = normalize(vec3<f32>(0.5, -0.6, 0.6));
    let diffuse = max(dot(n, l), 0.0) * 0.75 + max(dot(n, fill), 0.0) * 0.2;
    let hemi = mix(0.12, 0.28, n.y * 0.5 + 0.5);
    let h = normalize(l + v);
    let spec = pow(max(dot(n, h), 0.0), 48.0) * u.misc.x;
    let lit = base * (hemi + diffuse) + vec3<f32>(spec);
    let dist = -pos_view.z;
    let t = clamp((dist - u.fog.x) / max(u.fog.y - u.fog.x, 1e-3), 0.0, 1.0);
    return mix(lit, u.background.rgb, t * u.fog.z);
}

// ---------------------------------------------------------------- surface mesh

struct MeshIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec3<f32>,
};

struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) pos_view: vec3<f32>,
    @location(1) normal_view: vec3<f32>,
    @location(2) colour: vec3<f32>,
};

@vertex
fn vs_mesh(v: MeshIn) -> MeshOut {
    var o: MeshOut;
    let pv = u.view * vec4<f32>(v.position, 1.0);
    o.clip = u.proj * pv;
    o.pos_view = pv.xyz;
    o.normal_view = (u.view * vec4<f32>(v.normal, 0.0)).xyz;
    // A select, not an if: Mesa lavapipe (22.3) leaks memory on every draw whose vertex
    // shader branches (about 0.1 MiB per frame here).
    o.colour = select(v.colour, u.surface_colour.rgb, u.surface.y > 0.5);
    return o;
}

fn mesh_colour(i: MeshOut, front: bool) -> vec3<f32> {
    var n = i.normal_view;
    if (!front) {
        n = -n;
    }
    return shade(i.colour, n, i.pos_view);
}

@fragment
fn fs_mesh(i: MeshOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return vec4<f32>(mesh_colour(i, front), 1.0);
}

struct OitOut {
    @location(0) accum: vec4<f32>,
    @location(1) reveal: vec4<f32>,
};

// Weighted blended order-independent transparency (McGuire & Bavoil 2013): every layer adds its
// premultiplied colour times a depth weight; `reveal` multiplies the (1 - alpha) of all layers.
@fragment
fn fs_mesh_oit(i: MeshOut, @builtin(front_facing) front: bool) -> OitOut {
    let a = clamp(u.surface.x, 0.0, 1.0);
    let c = mesh_colour(i, front);
    let z = i.clip.z;
    let w = clamp(a * max(1e-2, 3e3 * pow(1.0 - z, 3.0)), 1e-2, 3e3);
    var o: OitOut;
    o.accum = vec4<f32>(c * a, a) * w;
    o.reveal = vec4<f32>(a, 0.0, 0.0, 0.0);
    return o;
}

// ---------------------------------------------------------------- atoms: sphere impostors

struct SphereIn {
    @location(0) centre_radius: vec4<f32>,
    @location(1) colour: vec4<f32>,
};

struct SphereOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) pos_view: vec3<f32>,
    @location(1) @interpolate(flat) centre_view: vec3<f32>,
    @location(2) @interpolate(flat) radius: f32,
    @location(3) @interpolate(flat) colour: vec3<f32>,
};

fn quad_corner(vi: u32) -> vec2<f32> {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    return corners[vi % 6u];
}

@vertex
fn vs_sphere(@builtin(vertex_index) vi: u32, s: SphereIn) -> SphereOut {
    let r = s.centre_radius.w;
    let c = (u.view * vec4<f32>(s.centre_radius.xyz, 1.0)).xyz;
    // A camera-facing quad just in front of the sphere, large enough to cover its silhouette.
    let corner = quad_corner(vi);
    let p = vec3<f32>(c.xy + corner * r * 1.5, c.z + r);
    var o: SphereOut;
    o.clip = u.proj * vec4<f32>(p, 1.0);
    o.pos_view = p;
    o.centre_view = c;
    o.radius = r;
    o.colour = s.colour.rgb;
    return o;
}

struct SphereFrag {
    @location(0) colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_sphere(i: SphereOut) -> SphereFrag {
    var origin: vec3<f32>;
    var dir: vec3<f32>;
    if (u.fog.w > 0.5) {
        origin = vec3<f32>(i.pos_view.xy, 0.0);
        dir = vec3<f32>(0.0, 0.0, -1.0);
    } else {
        origin = vec3<f32>(0.0);
        dir = normalize(i.pos_view);
    }
    let oc = origin - i.centre_view;
    let b = dot(oc, dir);
    let cc = dot(oc, oc) - i.radius * i.radius;
    let disc = b * b - cc;
    if (disc < 0.0) {
        discard;
    }
    let t = -b - sqrt(disc);
    let hit = origin + t * dir;
    let clip = u.proj * vec4<f32>(hit, 1.0);
    var o: SphereFrag;
    o.colour = vec4<f32>(shade(i.colour, hit - i.centre_view, hit), 1.0);
    o.depth = clamp(clip.z / clip.w, 0.0, 1.0);
    return o;
}

// ---------------------------------------------------------------- bonds: instanced cylinders

// Segments around a cylinder; the vertex count per instance is CYLINDER_SEGMENTS * 6.
const CYLINDER_SEGMENTS: u32 = 12u;

struct CylinderIn {
    @location(0) start_radius: vec4<f32>,
    @location(1) end: vec4<f32>,
    @location(2) colour: vec4<f32>,
};

@vertex
fn vs_cylinder(@builtin(vertex_index) vi: u32, c: CylinderIn) -> MeshOut {
    let seg = vi / 6u;
    let k = vi % 6u;
    // Two triangles per side quad: (0,0) (1,0) (1,1) / (0,0) (1,1) (0,1) in (around, along).
    var around = array<u32, 6>(0u, 1u, 1u, 0u, 1u, 0u);
    var along = array<f32, 6>(0.0, 0.0, 1.0, 0.0, 1.0, 1.0);
    let angle = f32(seg + around[k]) / f32(CYLINDER_SEGMENTS) * 6.2831853;
    let a = c.start_radius.xyz;
    let b = c.end.xyz;
    let axis = normalize(b - a);
    var helper = vec3<f32>(1.0, 0.0, 0.0);
    if (abs(axis.x) > 0.9) {
        helper = vec3<f32>(0.0, 1.0, 0.0);
    }
    let e1 = normalize(cross(axis, helper));
    let e2 = cross(axis, e1);
    let n = cos(angle) * e1 + sin(angle) * e2;
    let p = mix(a, b, along[k]) + n * c.start_radius.w;
    var o: MeshOut;
    let pv = u.view * vec4<f32>(p, 1.0);
    o.clip = u.proj * pv;
    o.pos_view = pv.xyz;
    o.normal_view = (u.view * vec4<f32>(n, 0.0)).xyz;
    o.colour = c.colour.rgb;
    return o;
}

@fragment
fn fs_cylinder(i: MeshOut) -> @location(0) vec4<f32> {
    return vec4<f32>(shade(i.colour, i.normal_view, i.pos_view), 1.0);
}

//! Tests that every scalar `const` of every shader as the device compiles it (the compute
//! stages of [`super::shaders::ALL`] and the render passes of [`crate::render::SHADERS`]) is
//! accounted for: equal to the Rust constant it mirrors, or tied to the workgroup size of the
//! entry point that relies on it, or named as the shader's own tuning value. A constant added to
//! a shader without one of these fails here, and so does a twin that drifts. (The preludes'
//! constants have their own test in [`super::shaders`].)

use std::collections::BTreeMap;

use crate::gpu::{density, measure, scan};
use crate::render::pipelines;
use crate::surface::{analytic, curved};

/// A scalar WGSL constant's value (u32 and f32 constants; arrays are not scalars).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Value {
    U32(u32),
    F32(f32),
}

/// The scalar constants of `source` by name, with the x workgroup size of each compute entry
/// point by name.
fn constants_of(file: &str, source: &str) -> (BTreeMap<String, Value>, BTreeMap<String, u32>) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{file}: {}", e.emit_to_string(source)));
    let mut constants = BTreeMap::new();
    for (_, c) in module.constants.iter() {
        let name = c.name.clone().expect("named constant");
        let value = match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => Value::U32(v),
            naga::Expression::Literal(naga::Literal::F32(v)) => Value::F32(v),
            _ => continue,
        };
        constants.insert(name, value);
    }
    let sizes = module
        .entry_points
        .iter()
        .map(|e| (e.name.clone(), e.workgroup_size[0]))
        .collect();
    (constants, sizes)
}

/// Scalar constants by name, with the files each is declared in.
type Found = BTreeMap<String, (Value, Vec<String>)>;

/// Every scalar constant of `shaders` (the same name in several must agree), with the files
/// each is in, and every entry point's x workgroup size.
fn all_constants(shaders: &[(&str, &str)]) -> (Found, BTreeMap<String, u32>) {
    let (mut all, mut sizes) = (
        BTreeMap::<String, (Value, Vec<String>)>::new(),
        BTreeMap::new(),
    );
    for &(file, source) in shaders {
        let (constants, entry_sizes) = constants_of(file, source);
        for (name, value) in constants {
            let seen = all.entry(name.clone()).or_insert((value, Vec::new()));
            assert_eq!(
                seen.0, value,
                "`{name}` differs between {:?} and {file}",
                seen.1
            );
            seen.1.push(file.to_string());
        }
        sizes.extend(entry_sizes);
    }
    (all, sizes)
}

/// Checks `found` against the Rust twins, the workgroup ties and the shader-only names: every
/// constant must be one of them, and each must hold.
fn check(found: &Found, twins: &[(&str, Value)], ties: &[(&str, u32)], shader_only: &[&str]) {
    let mut wrong = Vec::new();
    for (name, (value, files)) in found {
        let twin = twins.iter().find(|(n, _)| n == name).map(|&(_, v)| v);
        let tie = ties
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, v)| Value::U32(v));
        match (twin.or(tie), shader_only.contains(&name.as_str())) {
            (Some(expected), _) if expected != *value => wrong.push(format!(
                "{name} in {files:?}: WGSL {value:?}, expected {expected:?}"
            )),
            (None, false) => wrong.push(format!(
                "{name} in {files:?} ({value:?}) has no Rust twin, workgroup tie or shader-only entry: add one"
            )),
            _ => {}
        }
    }
    for name in twins.iter().map(|t| t.0).chain(ties.iter().map(|t| t.0)) {
        if !found.contains_key(name) {
            wrong.push(format!("{name} is listed but no shader declares it"));
        }
    }
    assert!(wrong.is_empty(), "shader constants:\n{}", wrong.join("\n"));
}

#[test]
fn compute_stage_constants_match_rust_or_their_workgroups() {
    let (found, sizes) = all_constants(crate::gpu::shaders::ALL);
    let preludes: Vec<String> = crate::gpu::shaders::PRELUDES
        .iter()
        .flat_map(|&(f, s)| constants_of(f, s).0.into_keys())
        .collect();
    let found = found
        .into_iter()
        .filter(|(n, _)| !preludes.contains(n))
        .collect();
    let size = |entry: &str| {
        *sizes
            .get(entry)
            .unwrap_or_else(|| panic!("no entry `{entry}`"))
    };
    let twins = [
        ("RUN", Value::U32(density::RUN)),
        ("BLOCK", Value::U32(scan::SCAN_BLOCK as u32)),
        ("PARTIAL_GROUPS", Value::U32(measure::PARTIAL_GROUPS)),
        ("REFINE_REACH", Value::F32(analytic::REFINE_REACH)),
        ("REFINE_STEP", Value::F32(analytic::REFINE_STEP)),
        ("REFINE_ITERATIONS", Value::U32(analytic::REFINE_ITERATIONS)),
        (
            "PROJECT_ITERATIONS",
            Value::U32(analytic::PROJECT_ITERATIONS),
        ),
        (
            "PROJECT_POINTS_ITERATIONS",
            Value::U32(analytic::PROJECT_POINTS_ITERATIONS),
        ),
        (
            "PROJECT_POINTS_STEP",
            Value::F32(analytic::PROJECT_POINTS_STEP),
        ),
        ("MAX_LIFT", Value::F32(curved::MAX_LIFT)),
        ("SHARP_COS", Value::F32(curved::SHARP_COS)),
        ("SHARP_LEVEL", Value::U32(curved::SHARP_LEVEL as u32)),
    ];
    // Constants whose value is the thread count of the entry point that indexes by them.
    let ties = [
        // One staged atom per thread of a brick's workgroup.
        ("TILE", size("bricks_tiled")),
        // The scan's threads per block.
        ("WG", size("scan_blocks")),
    ];
    check(&found, &twins, &ties, &["MAX_SORTED", "PER"]);
    // The scan's block is its threads times the values each thread takes.
    let u = |n: &str| match found[n].0 {
        Value::U32(v) => v,
        Value::F32(_) => panic!("{n} is not a u32"),
    };
    assert_eq!(u("WG") * u("PER"), u("BLOCK"), "scan: WG * PER != BLOCK");
    // The final sum's one workgroup reads one partial per thread.
    assert_eq!(
        size("final_sum"),
        measure::PARTIAL_GROUPS,
        "final_sum threads"
    );
}

#[test]
fn render_constants_match_rust() {
    let (found, _) = all_constants(crate::render::SHADERS);
    let twins = [(
        "CYLINDER_SEGMENTS",
        Value::U32(pipelines::CYLINDER_SEGMENTS),
    )];
    // The ambient occlusion's samples per pixel, the shadow ray's steps and the outline's
    // distance for the background are the look's own.
    check(
        &found,
        &twins,
        &[],
        &["SAMPLES", "SHADOW_STEPS", "FAR_AWAY"],
    );
}

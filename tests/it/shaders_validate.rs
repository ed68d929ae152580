//! Validates every WGSL file under `shaders/` with naga (parse + full validation), no GPU needed,
//! and checks that the edge table `emit.wgsl` hard-codes agrees with the Rust side (the shared
//! constants of the preludes are checked by the unit tests of `mdsurf::gpu::shaders`).

use std::path::{Path, PathBuf};

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries =
        std::fs::read_dir(dir).unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            wgsl_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
}

/// Parses and fully validates one WGSL source with naga; `Err` holds naga's report.
fn validate(name: &str, source: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    );
    validator
        .validate(&module)
        .map(|_| ())
        .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))
}

/// Every file under `shaders/` is validated: each stage as the engine or the renderer
/// assembles it (`mdsurf::gpu::shaders::ALL`, `mdsurf::render::SHADERS`, with their shared
/// uniform and constant files prepended), the shared files alone (the uniforms and the preludes
/// of `mdsurf::gpu::shaders::PRELUDES`), and the shared function files (`brick_samples.wgsl`,
/// `class_entries.wgsl`, `field.wgsl`) inside the stages that include them. A new shader that
/// neither lists fails here.
#[test]
fn every_shader_parses_and_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut files = Vec::new();
    wgsl_files(&dir, &mut files);
    files.sort();
    let assembled: Vec<(&str, &str)> = mdsurf::gpu::shaders::ALL
        .iter()
        .chain(mdsurf::render::SHADERS)
        .copied()
        .collect();
    let mut shared = vec!["slab_uniform.wgsl", "render_view.wgsl"];
    shared.extend(mdsurf::gpu::shaders::PRELUDES.iter().map(|(n, _)| *n));
    // Shared functions that use names each stage declares: checked inside the stages.
    let included = ["brick_samples.wgsl", "class_entries.wgsl", "field.wgsl"];
    let mut failures = Vec::new();
    for file in &files {
        let name = file
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        let on_disk = std::fs::read_to_string(file).expect("readable shader");
        let result = match assembled.iter().find(|(n, _)| *n == name) {
            Some((_, source)) => {
                assert!(
                    source.ends_with(&on_disk),
                    "{name}: the compiled source is not this file"
                );
                validate(name, source)
            }
            None if shared.contains(&name) => validate(name, &on_disk),
            None if included.contains(&name) => {
                let users = assembled.iter().filter(|(_, s)| s.contains(&on_disk));
                match users.count() {
                    0 => Err(format!("{name}: no stage includes it")),
                    _ => Ok(()),
                }
            }
            None => Err(format!(
                "{name}: neither a shared file nor listed in gpu::shaders::ALL or render::SHADERS"
            )),
        };
        failures.extend(result.err());
    }
    for (name, _) in &assembled {
        assert!(
            files.iter().any(|f| f.ends_with(name)),
            "{name} is listed but missing from {}",
            dir.display()
        );
    }
    assert!(
        failures.is_empty(),
        "invalid shaders:\n{}",
        failures.join("\n")
    );
}

#[test]
fn edge_corner_table_in_emit_matches_the_rust_tables() {
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/emit.wgsl"))
        .expect("emit.wgsl");
    let line = source
        .lines()
        .find(|l| l.starts_with("const EDGE_CORNER0"))
        .expect("EDGE_CORNER0 in emit.wgsl");
    let inner = line
        .rsplit_once("array<u32, 12>(")
        .expect("array literal")
        .1;
    let values: Vec<u8> = inner
        .trim_end_matches(");")
        .split(',')
        .map(|v| v.trim().trim_end_matches('u').parse().expect("number"))
        .collect();
    let expected: Vec<u8> = mdsurf::surface::tables::EDGE_CORNERS
        .iter()
        .map(|e| e[0])
        .collect();
    assert_eq!(values, expected);
    for (e, corners) in mdsurf::surface::tables::EDGE_CORNERS.iter().enumerate() {
        let (a, b) = (corners[0], corners[1]);
        assert_eq!(
            b - a,
            1 << (e / 4),
            "edge {e} must run along axis {}",
            e / 4
        );
    }
}

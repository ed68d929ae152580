//! `mdsurf render --script FILE`: a console session replayed headless. The script's lines run
//! first, as in the window's console (see `mdsurf::app::headless_script`): `screenshot` lines
//! write their pictures, `rep`, `frame`, `fit` and `view open` set up the scene. The state the
//! script leaves then stands in for `--state`, so `-o` (a picture, numbered images or a movie)
//! shows the scene the script built.

use std::path::Path;

use anyhow::{Result, anyhow, bail};
use glam::Vec3;
use mdsurf::app::headless_script::{ScriptSetup, run_script};
use mdsurf::app::source::open_files_with;
use mdsurf::app::worker::Engine;
use mdsurf::gpu::{Picked, pick_engine};
use mdsurf::model::{Frame, ParticleOptions};
use mdsurf::render::AtomStyle;
use mdsurf::render::HeadlessGpu;
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::state_file::StateFile;
use mdsurf::surface::CpuEngine;

use super::common::Backend;

use super::render_args::RenderArgs;

/// Runs the script at `path` on the files of `args` (starting from `state`, the `--state`
/// file, when given) and returns the state it leaves. Errors name the script and the line.
pub(crate) fn run(
    args: &RenderArgs,
    path: &Path,
    state: Option<StateFile>,
    look: mdsurf::render::RenderSettings,
) -> Result<StateFile> {
    if args.live.options(args.input.traj.as_deref())?.is_some() {
        bail!("--script: a script runs on a trajectory file, not on --imd or --follow");
    }
    let lines = mdsurf::app::console::read_script(path).map_err(|e| anyhow!(e))?;
    let transforms = args.transforms.options(state.as_ref());
    let source = open_files_with(&args.input.top, args.input.traj.as_deref(), &transforms)
        .map_err(|e| anyhow!(e))?;
    let gpu = HeadlessGpu::new().map_err(|e| {
        anyhow!(
            "--script draws pictures: {e} ({})",
            mdsurf::gpu::SOFTWARE_ADAPTER
        )
    })?;
    let cpu = || Engine::Host(Box::new(CpuEngine::new()));
    let engine = match args.backend {
        Backend::Cpu => cpu(),
        _ if transforms.periodic => cpu(),
        backend => match pick_engine(backend.into(), Some(gpu.context.clone()))? {
            Picked::Gpu(engine) => Engine::Gpu(engine),
            Picked::Cpu { .. } => cpu(),
        },
    };
    let params = args.params.params()?;
    let particles = args.input.particles.options()?;
    let mut base = Representation::new("selection", "all", RepStyle::Surface);
    base.set_params(&params);
    base.radii = args.params.radius_set();
    base.colour = particles.colours;
    base.vertices = args.params.vertex_mode();
    // Without a state file the script starts from the representations the flags choose, as a
    // render without a script would show them (--select, --opacity, --atoms, --beads).
    let reps = match &state {
        Some(_) => None,
        None => {
            let topology = source.topology();
            // Static selections only: the default classes need no coordinates.
            let placeholder = Frame {
                positions: vec![Vec3::ZERO; topology.len()],
                ..Frame::default()
            };
            let radii = (&params, args.params.radius_set());
            let mut choice = args.scene.representations(
                None,
                topology,
                &placeholder,
                radii,
                &particles,
                true,
            )?;
            args.params.apply_to_reps(&mut choice.reps, false);
            apply_rep_flags(args, &mut choice.reps, &particles);
            Some(choice.reps)
        }
    };
    let setup = ScriptSetup {
        gpu: &gpu.context,
        engine,
        source,
        start: state,
        reps,
        base,
        render: look,
        size: args.size,
    };
    let quiet = args.quiet;
    let mut print = |line: &str| {
        if !quiet {
            eprintln!("{line}");
        }
    };
    let mut left = run_script(setup, path, &lines, &mut print)?;
    left.trajectory.set_transforms(&transforms);
    Ok(left)
}

/// The look flags that are per representation, on representations chosen by the flags (not
/// by a state file): `--opacity` applies to the first one (the selection, or the default
/// macromolecule surface), and `--atoms` adds atoms of the same selection.
pub(crate) fn apply_rep_flags(
    args: &RenderArgs,
    reps: &mut Vec<Representation>,
    options: &ParticleOptions,
) {
    if let Some(main) = reps.first_mut() {
        main.opacity = args.opacity;
    }
    if args.atoms != AtomStyle::Hidden {
        let selection = args.scene.select.clone().unwrap_or_else(|| "all".into());
        let style = match args.atoms {
            AtomStyle::Spheres => RepStyle::Spheres,
            AtomStyle::Sticks => RepStyle::Sticks,
            _ => RepStyle::BallAndStick,
        };
        reps.push(Representation {
            colour: options.colours,
            ..Representation::new("atoms", &selection, style)
        });
    }
}

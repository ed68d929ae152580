//! What `surface` and `render` share about representations: `--select EXPR` (one surface
//! representation of that selection with the command's H/R/I/quality/colour), `--state FILE`
//! (the representations of a state file saved by the viewer), or, with neither, the default
//! representations of the system (printed on stderr).

use std::path::PathBuf;

use anyhow::{Result, anyhow, bail};
use mdsurf::model::{Frame, ParticleOptions, RadiusOverrides, Topology};
use mdsurf::scene::defaults::{default_representations, describe};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::state_file::StateFile;
use mdsurf::scene::{RepRequest, SceneEngine};
use mdsurf::surface::{RadiusSet, SurfaceParams};

/// Which representations a headless command computes or draws.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// One surface of the atoms this selection picks, e.g. 'protein', 'resname POPE POPG',
    /// 'within 5 of resname LIG' (without --select or --state: the default representations).
    #[arg(long, value_name = "EXPR")]
    pub select: Option<String>,
    /// The representations (and camera and look, for render) of a state file saved by the
    /// viewer (File → Save view).
    #[arg(long, value_name = "STATE.toml", conflicts_with = "select")]
    pub state: Option<PathBuf>,
}

/// The representations a command uses and where they came from.
pub struct SceneChoice {
    /// The representations, in drawing order.
    pub reps: Vec<Representation>,
    /// The state file, when `--state` gave one.
    pub state: Option<StateFile>,
    /// One line per default representation, for stderr (empty unless the defaults are used).
    pub described: Vec<String>,
}

impl SceneChoice {
    /// Prints the default representations on stderr (nothing for `--select` / `--state`).
    pub fn print_defaults(&self) {
        for line in &self.described {
            eprintln!("{line}");
        }
    }
}

impl SceneArgs {
    /// Loads the state file, if any (before any data is read, so a bad file fails fast).
    pub fn load_state(&self) -> Result<Option<StateFile>> {
        self.state
            .as_deref()
            .map(|p| StateFile::load(p).map_err(|e| anyhow!(e)))
            .transpose()
    }

    /// The representations for `topology`: from `state`, from `--select`, or the defaults
    /// (described for stderr unless `quiet`; see [`SceneChoice::print_defaults`]). The surface
    /// parameters and radius set, and `options` (colours and beads), are the command's, used by
    /// `--select` and the defaults.
    pub fn representations(
        &self,
        state: Option<StateFile>,
        topology: &Topology,
        first: &Frame,
        (params, radii): (&SurfaceParams, RadiusSet),
        options: &ParticleOptions,
        quiet: bool,
    ) -> Result<SceneChoice> {
        let style = if options.beads {
            RepStyle::Beads
        } else {
            RepStyle::Surface
        };
        let mut base = Representation::new("selection", "all", style);
        base.set_params(params);
        base.radii = radii;
        base.colour = options.colours;
        if let Some(state) = state {
            return Ok(SceneChoice {
                reps: state.representations.clone(),
                state: Some(state),
                described: Vec::new(),
            });
        }
        if let Some(expr) = &self.select {
            let rep = Representation {
                selection: expr.clone(),
                ..base
            };
            rep.validate().map_err(|e| anyhow!(e))?;
            return Ok(SceneChoice {
                reps: vec![rep],
                state: None,
                described: Vec::new(),
            });
        }
        let mut reps = default_representations(topology, first, &base);
        for r in reps.iter_mut().filter(|r| r.style.is_surface()) {
            r.style = if options.beads && r.visible {
                RepStyle::Beads
            } else {
                r.style
            };
        }
        let described = if quiet {
            Vec::new()
        } else {
            describe(&reps, topology, first)
        };
        Ok(SceneChoice {
            reps,
            state: None,
            described,
        })
    }
}

/// Numbers the visible representations of `reps` for `scene` (ids 0, 1, ... in order) and binds
/// them to `topology` with `radius_overrides`; a visible representation whose static selection picks no atom in `first`
/// is an error naming it (`--select 'resname XYZ'` on a file without XYZ).
pub fn bind_scene(
    scene: &mut SceneEngine,
    reps: &[Representation],
    topology: &Topology,
    first: &Frame,
    radius_overrides: &RadiusOverrides,
    files: &str,
) -> Result<Vec<RepRequest>> {
    scene.reset(topology, radius_overrides);
    let requests: Vec<RepRequest> = reps
        .iter()
        .filter(|r| r.visible)
        .enumerate()
        .map(|(id, rep)| RepRequest {
            id: id as u64,
            rep: rep.clone(),
        })
        .collect();
    scene.bind(topology, &requests)?;
    for RepRequest { id, rep } in &requests {
        if let Some(layer) = scene.layer(*id)
            && !layer.is_dynamic()
            && layer.atoms(first).is_empty()
        {
            bail!(
                "{files}: selection '{}' of representation '{}' matches no atom",
                rep.selection,
                rep.name
            );
        }
    }
    Ok(requests)
}

//! `mdsurf surface`'s measurements beyond one area and volume per representation
//! ([`mdsurf::measure`]): areas per atom and per residue (`--per-atom`, `--per-residue`, with
//! each residue's exposure), enclosed cavities tracked over the frames (`--cavities`), and the
//! buried area between two selections (`--interface A B`, rows in `--interface-csv`, contact
//! residues in `--interface-residues`). Each frame of the scene engine is handed to
//! [`Measurer::frame`]; the CSVs are written atomically at the end, with the rows of every frame
//! that was computed.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use mdsurf::export::stats_merge::{PartHeader, part_path};
use mdsurf::measure::{
    self, AtomCsv, CavityCsv, CavityEventCsv, CavityOptions, CavityTracker, ContactCsv,
    ExposureTable, InterfaceCsv, ResidueCsv,
};
use mdsurf::model::pbc::PbcCell;
use mdsurf::model::{Frame, RadiusOverrides, Topology};
use mdsurf::scene::interface::{Interface as SceneInterface, InterfaceFrame, ShownSurface};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::{LayerResult, SceneEngine, SceneFrame};
use mdsurf::surface::{AtomSet, CpuEngine, RadiusSet, SurfaceParams, VertexMode};

/// Measurement flags of `mdsurf surface`.
#[derive(clap::Args, Debug, Clone)]
pub struct MeasureArgs {
    /// Area per residue (Å²) and exposure (area over the residue type's area alone) of every
    /// surface representation and frame: frame,rep,chain,resid,resname,area_A2,exposure,residue
    /// (residue: its index in the file from 0, as `residue N` selects it).
    #[arg(long, value_name = "FILE.csv")]
    pub per_residue: Option<PathBuf>,
    /// Area per atom (Å²): frame,rep,serial,name,chain,resid,resname,area_A2,residue.
    #[arg(long, value_name = "FILE.csv")]
    pub per_atom: Option<PathBuf>,
    /// Enclosed cavities of every surface representation, tracked over frames:
    /// frame,rep,cavity_id,volume_A3,area_A2,cx,cy,cz,lining.
    #[arg(long, value_name = "FILE.csv")]
    pub cavities: Option<PathBuf>,
    /// What tracking the cavities saw (the ids of `--cavities`): frame,rep,event,cavity_id,ids
    /// with event birth, death, merge (cavity_id continues, ids ended) or split (ids split off
    /// cavity_id).
    #[arg(long, value_name = "FILE.csv")]
    pub cavity_events: Option<PathBuf>,
    /// Smallest cavity reported, in Å³ (smaller voids are mostly gaps between a few atoms).
    #[arg(long, value_name = "A3", default_value_t = 1.0, value_parser = parse_volume,
          allow_negative_numbers = true)]
    pub min_cavity_volume: f64,
    /// Find cavities as the solvent-excluded surface does instead of from the Gaussian
    /// surface: voids where a probe of this radius in Å fits (1.4 for water) that it cannot
    /// reach from outside, with Bondi's radii; volume and area of the probe-swept void (MSMS's
    /// inner components). Finds pockets with a mouth narrower than the probe.
    #[arg(long, value_name = "A", value_parser = parse_probe)]
    pub cavity_probe: Option<f32>,
    /// Buried area between two selections, (area(A) + area(B) - area(A or B)) / 2, the three
    /// surfaces on one grid (CPU engine, the command's H, R, I and quality; the --select
    /// surface is the complex when it holds exactly both sides). Under --preset ses
    /// it is within 2 % of MSMS's buried SES on a large interface (1hpv) but 11 to 20 % above
    /// it on small ones (1a28, 7ddo); --interface-probe 1.4 measures the SES itself.
    #[arg(long, num_args = 2, value_names = ["SEL_A", "SEL_B"])]
    pub interface: Option<Vec<String>>,
    /// Where the interface rows go: frame,time_ps,area_a_A2,area_b_A2,area_ab_A2,buried_A2,
    /// contacts_a,contacts_b (the residues that lose more than --contact-threshold each).
    /// Without it the buried area is printed per frame.
    #[arg(long, value_name = "FILE.csv", requires = "interface")]
    pub interface_csv: Option<PathBuf>,
    /// The contact residues of every frame, one row each:
    /// frame,time_ps,side,chain,resid,resname,area_alone_A2,area_complex_A2,buried_A2,residue
    /// (side A or B; buried = the residue's area alone minus in the complex; residue: its index
    /// in the file from 0).
    #[arg(long, value_name = "FILE.csv", requires = "interface")]
    pub interface_residues: Option<PathBuf>,
    /// A residue is a contact when it loses more than this area in Å² from alone to the
    /// complex (0: every residue that loses any).
    #[arg(long, value_name = "A2", default_value_t = measure::CONTACT_THRESHOLD,
          value_parser = parse_area, requires = "interface", allow_negative_numbers = true)]
    pub contact_threshold: f64,
    /// Measure the interface on the solvent-excluded surface a probe of this radius in Å leaves
    /// (1.4 for water; Bondi's radii, a 0.25 Å grid) instead of on the Gaussian surface: the
    /// buried SES area MSMS, FreeSASA-style tools and PISA-like analyses report.
    #[arg(long, value_name = "A", value_parser = parse_probe, requires = "interface")]
    pub interface_probe: Option<f32>,
}

impl MeasureArgs {
    /// True when the surfaces' meshes are needed on the host.
    pub fn needs_meshes(&self) -> bool {
        self.per_residue.is_some() || self.per_atom.is_some() || self.tracks_cavities()
    }

    /// True when the frame's surfaces must keep their meshes: measured, or one of them may be
    /// the complex of a Gaussian interface whose contact residues are listed (their per-atom
    /// areas are weighed on its mesh).
    pub fn keeps_meshes(&self) -> bool {
        self.needs_meshes() || (self.gaussian_interface() && self.lists_contacts())
    }

    /// True when the frame's surfaces keep their sampled density: one of them may be the
    /// complex of a Gaussian interface, whose larger side is then its density less the other
    /// side's ([`mdsurf::measure::interface_on`]).
    pub fn keeps_density(&self) -> bool {
        self.gaussian_interface()
    }

    /// True when `--interface` measures on the Gaussian surface (not `--interface-probe`).
    fn gaussian_interface(&self) -> bool {
        self.interface.is_some() && self.interface_probe.is_none()
    }

    /// True when a table lists the interface's contact residues (`--interface-csv` or
    /// `--interface-residues`).
    pub fn lists_contacts(&self) -> bool {
        self.interface_csv.is_some() || self.interface_residues.is_some()
    }

    /// True when cavities are found and tracked (`--cavities` or `--cavity-events`).
    pub fn tracks_cavities(&self) -> bool {
        self.cavities.is_some() || self.cavity_events.is_some()
    }

    /// Fails with one line when `--chunk` comes with a table that needs every frame in one
    /// process: cavity ids are tracked from frame to frame.
    pub fn check_chunk(&self, chunked: bool) -> Result<()> {
        if chunked && self.tracks_cavities() {
            bail!(
                "--chunk: cavity ids are tracked from frame to frame in one process: run --cavities and --cavity-events without --chunk (the per-residue, per-atom and interface tables can be split)"
            );
        }
        Ok(())
    }

    /// The output files asked for.
    pub fn outputs(&self) -> Vec<&Path> {
        [
            &self.per_residue,
            &self.per_atom,
            &self.cavities,
            &self.cavity_events,
            &self.interface_csv,
            &self.interface_residues,
        ]
        .into_iter()
        .filter_map(|p| p.as_deref())
        .collect()
    }
}

/// A volume in Å³: finite and not negative.
fn parse_volume(s: &str) -> Result<f64, super::arg_error::ArgError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(super::arg_error::ArgError::Volume(s.to_string())),
    }
}

/// An area in Å²: finite and not negative.
fn parse_area(s: &str) -> Result<f64, super::arg_error::ArgError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(super::arg_error::ArgError::Area(s.to_string())),
    }
}

/// A probe radius in Å: a finite number from 0.1 to 10.
fn parse_probe(s: &str) -> Result<f32, super::arg_error::ArgError> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (0.1..=10.0).contains(&v) => Ok(v),
        _ => Err(super::arg_error::ArgError::Probe(s.to_string())),
    }
}

/// The two sides of `--interface`, bound to the topology, and the CSV rows so far.
struct Interface {
    sides: SceneInterface,
    /// Contact threshold in Å², when a table lists the contact residues (otherwise they are
    /// not looked for, nor the per-atom areas they need weighed).
    threshold: Option<f64>,
    rows: InterfaceCsv,
    residues: ContactCsv,
}

/// Collects the measurements frame by frame.
pub struct Measurer {
    args: MeasureArgs,
    residues: ResidueCsv,
    atoms: AtomCsv,
    cavities: CavityCsv,
    cavity_events: CavityEventCsv,
    trackers: HashMap<String, CavityTracker>,
    exposure: HashMap<String, ExposureTable>,
    interface: Option<Interface>,
    /// With `--chunk`: the part header; each table goes to its part file.
    part: Option<PartHeader>,
}

impl Measurer {
    /// Checks the flags against the system (selections bind and pick atoms in `first`) and
    /// starts empty tables. The interface's surfaces start from the radii of `radii` and place
    /// their vertices by `vertices` (the preset's unless `--vertices` says otherwise), as the
    /// reported surfaces do.
    pub fn new(
        args: &MeasureArgs,
        topology: &Topology,
        first: &Frame,
        radius_overrides: &RadiusOverrides,
        params: &SurfaceParams,
        radii: RadiusSet,
        vertices: VertexMode,
    ) -> Result<Measurer> {
        if args.cavity_probe.is_some() && !args.tracks_cavities() {
            bail!(
                "--cavity-probe says how cavities are found: add --cavities FILE.csv or --cavity-events FILE.csv"
            );
        }
        let interface = match args.interface.as_deref() {
            Some([a, b]) => {
                let mut base = Representation::new("interface", "all", RepStyle::Surface);
                base.set_params(params);
                base.radii = radii;
                base.vertices = vertices;
                let sides = SceneInterface::new(
                    topology,
                    [a, b],
                    &base,
                    radius_overrides,
                    args.interface_probe,
                )
                .map_err(|e| anyhow!("--interface: {e}"))?;
                sides
                    .check_sides(topology, first)
                    .map_err(|e| anyhow!("--interface: {e}"))?;
                Some(Interface {
                    sides,
                    threshold: args.lists_contacts().then_some(args.contact_threshold),
                    rows: InterfaceCsv::new(),
                    residues: ContactCsv::new(),
                })
            }
            Some(_) => bail!("--interface takes two selections"),
            None => None,
        };
        Ok(Measurer {
            args: args.clone(),
            residues: ResidueCsv::new(),
            atoms: AtomCsv::new(),
            cavities: CavityCsv::new(),
            cavity_events: CavityEventCsv::new(),
            trackers: HashMap::new(),
            exposure: HashMap::new(),
            interface,
            part: None,
        })
    }

    /// Makes the measurements follow periodic surfaces (`--periodic`): the interface's three
    /// surfaces are then periodic in each frame's cell; the probes' surfaces are not, and are
    /// refused.
    pub fn set_periodic(&mut self, periodic: bool) -> Result<()> {
        if periodic && self.args.cavity_probe.is_some() {
            bail!(
                "--cavity-probe finds a probe's cavities in open space, not in a periodic cell: leave out --cavity-probe (the periodic surface's own cavities are found) or --periodic"
            );
        }
        if let Some(interface) = self.interface.as_mut() {
            interface
                .sides
                .set_periodic(periodic)
                .map_err(|e| anyhow!("--interface: {e}"))?;
        }
        Ok(())
    }

    /// Writes the tables as the parts of chunk `header` (`FILE.part-IIII-of-NNNN.csv`, the
    /// header their first line), which `mdsurf merge FILE.csv` joins.
    pub fn set_part(&mut self, header: PartHeader) {
        self.part = Some(header);
    }

    /// True when the per-residue exposure is asked for: its table of residues alone is built
    /// from the run's first frame (see [`Measurer::prime_exposure`]).
    pub fn needs_exposure(&self) -> bool {
        self.args.per_residue.is_some()
    }

    /// Builds the exposure tables from `computed`, the run's first frame, without adding rows,
    /// so that a chunk that starts later gives the exposures one process would.
    pub fn prime_exposure(
        &mut self,
        topology: &Topology,
        frame: &Frame,
        computed: &SceneFrame,
        scene: &SceneEngine,
    ) -> Result<()> {
        for layer in computed.surfaces() {
            let indices = layer_atoms(scene, layer, frame)?;
            let (atoms, params) = measured_atoms(layer);
            self.exposure_table(
                topology,
                &layer.rep.name,
                indices.as_deref(),
                &atoms,
                PbcCell::of(frame),
                &params,
            )
            .with_context(|| {
                format!(
                    "frame {}: representation '{}'",
                    computed.frame, layer.rep.name
                )
            })?;
        }
        Ok(())
    }

    /// Builds representation `name`'s exposure table unless it has one (residues made whole
    /// in the frame's `cell`, if any).
    fn exposure_table(
        &mut self,
        topology: &Topology,
        name: &str,
        atom_indices: Option<&[u32]>,
        atoms: &AtomSet<'_>,
        cell: Option<PbcCell>,
        params: &SurfaceParams,
    ) -> Result<()> {
        if self.exposure.contains_key(name) {
            return Ok(());
        }
        if !measure::names_residues(topology, atom_indices) {
            bail!(
                "--per-residue: its atoms are in no residue (the file names none, as LAMMPS \
                 dumps and XYZ files do): use --per-atom"
            );
        }
        let mut engine = CpuEngine::new();
        let table = ExposureTable::from_isolated_residues(
            &mut engine,
            topology,
            atom_indices,
            atoms,
            cell.as_ref(),
            params,
        )?;
        self.exposure.insert(name.to_string(), table);
        Ok(())
    }

    /// Measures one computed frame (`frame`: its transformed coordinates); `scene` gives each
    /// representation's atoms. Errors name the frame and representation.
    pub fn frame(
        &mut self,
        topology: &Topology,
        frame: &Frame,
        computed: &SceneFrame,
        scene: &SceneEngine,
        quiet: bool,
    ) -> Result<()> {
        let index = computed.frame;
        // Each surface's topology atoms, found once for the measurements and the interface.
        let layers: Vec<(&LayerResult, Result<Option<Vec<u32>>>)> =
            if self.args.needs_meshes() || self.interface.is_some() {
                computed
                    .surfaces()
                    .map(|layer| (layer, layer_atoms(scene, layer, frame)))
                    .collect()
            } else {
                Vec::new()
            };
        if self.args.needs_meshes() {
            for (layer, atoms) in &layers {
                let atoms = atoms.as_ref().map_err(|e| anyhow!("{e:#}"))?;
                self.surface(topology, (index, frame), layer, atoms.as_deref())
                    .with_context(|| {
                        format!("frame {index}: representation '{}'", layer.rep.name)
                    })?;
            }
        }
        if let Some(interface) = self.interface.as_mut() {
            // The frame's surfaces, one of which may be the interface's complex: those of the
            // CPU engine, which the interface's sides are computed with (another engine's
            // vertices and sums could differ from theirs by more than rounding).
            let same_engine = scene.name() == "cpu";
            let shown: Vec<ShownSurface<'_>> = layers
                .iter()
                .filter(|_| same_engine)
                .filter_map(|(layer, atoms)| match atoms {
                    Ok(Some(atoms)) => Some(ShownSurface {
                        layer,
                        atoms,
                        particles: scene.layer(layer.id).and_then(|l| l.particles()),
                    }),
                    _ => None,
                })
                .collect();
            let line = interface
                .frame(topology, frame, computed.time_ps, index, &shown)
                .with_context(|| format!("frame {index}: --interface"))?;
            if self.args.interface_csv.is_none() && !quiet {
                eprintln!("{line}");
            }
        }
        Ok(())
    }

    /// Per-atom, per-residue and cavity rows of one surface representation in frame `index`
    /// (`frame`: its transformed coordinates).
    fn surface(
        &mut self,
        topology: &Topology,
        (index, frame): (usize, &Frame),
        layer: &LayerResult,
        atom_indices: Option<&[u32]>,
    ) -> Result<()> {
        let (atoms, params) = measured_atoms(layer);
        let name = &layer.rep.name;
        if self.args.per_residue.is_some() || self.args.per_atom.is_some() {
            let areas = measure::atom_areas_of(&layer.output, &atoms, &params)?;
            if self.args.per_atom.is_some() {
                self.atoms
                    .push(index, name, topology, atom_indices, &areas)?;
            }
            if self.args.per_residue.is_some() {
                let cell = PbcCell::of(frame);
                self.exposure_table(topology, name, atom_indices, &atoms, cell, &params)?;
                let residues = measure::residue_areas(topology, atom_indices, &areas)?;
                self.residues
                    .push(index, name, topology, &residues, self.exposure.get(name));
            }
        }
        if self.args.tracks_cavities() {
            let options = CavityOptions {
                min_volume: self.args.min_cavity_volume,
                ..CavityOptions::default()
            };
            let found = match self.args.cavity_probe {
                Some(probe) => {
                    let probe_options = measure::ProbeOptions {
                        probe,
                        min_volume: options.min_volume,
                        ..measure::ProbeOptions::default()
                    };
                    measure::ses_probe_cavities(topology, atom_indices, &atoms, &probe_options)?
                }
                None => measure::cavities_of(&layer.output, &atoms, &params, &options)?,
            };
            let tracked = self
                .trackers
                .entry(name.clone())
                .or_default()
                .update(index, &found);
            self.cavities
                .push(index, name, topology, atom_indices, &tracked.cavities)?;
            self.cavity_events.push(index, name, &tracked.events);
        }
        Ok(())
    }

    /// Writes every table asked for (atomically; with `--chunk`, to its part file).
    pub fn finish(self) -> Result<()> {
        let a = &self.args;
        let first = self.part.as_ref().map(PartHeader::line);
        let first = first.as_deref();
        let path = |path: &PathBuf| match &self.part {
            Some(h) => part_path(path, h.index, h.count),
            None => path.clone(),
        };
        if let Some(p) = &a.per_residue {
            self.residues.write(&path(p), first)?;
        }
        if let Some(p) = &a.per_atom {
            self.atoms.write(&path(p), first)?;
        }
        if let Some(p) = &a.cavities {
            self.cavities.write(&path(p), first)?;
        }
        if let Some(p) = &a.cavity_events {
            self.cavity_events.write(&path(p), first)?;
        }
        if let (Some(p), Some(interface)) = (&a.interface_csv, &self.interface) {
            interface.rows.write(&path(p), first)?;
        }
        if let (Some(p), Some(interface)) = (&a.interface_residues, &self.interface) {
            interface.residues.write(&path(p), first)?;
        }
        Ok(())
    }
}

impl Interface {
    /// The buried area of frame `index`: appends its CSV rows and returns a one-line summary.
    fn frame(
        &mut self,
        topology: &Topology,
        frame: &Frame,
        time_ps: Option<f64>,
        index: usize,
        shown: &[ShownSurface<'_>],
    ) -> Result<String> {
        let InterfaceFrame {
            result, contacts, ..
        } = self
            .sides
            .measure_on(topology, frame, self.threshold, shown)?;
        self.rows.push(index, time_ps, topology, &result, &contacts);
        self.residues.push(index, time_ps, topology, &contacts);
        Ok(format!(
            "frame {index}: buried area {:.1} Å² (A {:.1}, B {:.1}, together {:.1} Å²)",
            result.buried, result.area_a, result.area_b, result.area_complex
        ))
    }
}

/// The atoms `layer`'s surface was computed from, and the parameters the engine computed it
/// with (refined vertices run at quality max).
fn measured_atoms(layer: &LayerResult) -> (AtomSet<'_>, SurfaceParams) {
    let p = &layer.particles;
    let atoms = AtomSet {
        positions: &p.positions,
        radii: &p.radii,
        colours: None,
    };
    (atoms, layer.measured_params())
}

/// The topology atoms behind `layer`'s particles (`None`: every atom); beads have none.
fn layer_atoms(
    scene: &SceneEngine,
    layer: &LayerResult,
    frame: &Frame,
) -> Result<Option<Vec<u32>>> {
    if layer.beads {
        bail!(
            "representation '{}': per-atom, per-residue and cavity measurements need atoms, not beads",
            layer.rep.name
        );
    }
    let Some(bound) = scene.layer(layer.id) else {
        bail!("representation '{}' is not bound", layer.rep.name);
    };
    let atoms = bound.atoms(frame);
    if atoms.len() != layer.particles.positions.len() {
        bail!(
            "representation '{}': {} atoms selected but {} particles",
            layer.rep.name,
            atoms.len(),
            layer.particles.positions.len()
        );
    }
    Ok(Some(atoms))
}

//! The SES preset's exposure radii on the GPU (issue 33 section 3, `shaders/exposure.wgsl`,
//! `mdsurf::gpu::exposure`): the device's heavy-neighbour counts and radii equal the host's
//! (`mdsurf::model::exposure::heavy_neighbour_counts`, `ExposureModel::apply`) exactly, on
//! proteins, on a frame of adk in water and on atoms placed within an ulp of the counting
//! radius; and the engine's SES surface with the exposure counted on the device has the area it
//! has with the host's radii, directly and through the scene engine. Small cases for lavapipe.

use std::sync::Arc;

use crate::data_support::data;
use crate::gpu_support::engine;
use glam::Vec3;
use mdsurf::gpu::GpuEngine;
use mdsurf::gpu::tolerance as tol;
use mdsurf::model::exposure::{ExposureModel, heavy_neighbour_counts};
use mdsurf::model::{Frame, ParticleOptions, Particles, RadiusOverrides, Topology};
use mdsurf::scene::layer::Layer;
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::{RepRequest, SceneBackend, SceneEngine};
use mdsurf::surface::{
    AtomSet, Preset, RadiusSet, SurfaceEngine, SurfaceOutput, SurfaceParams, VertexMode,
};

/// Runs one GPU frame of `positions` with their own `radii` (Å) and the exposure counted on
/// the device under `model` (`heavy`: one flag per atom); returns (counts, radii) read back.
fn device_exposure(
    engine: &mut GpuEngine,
    positions: &[Vec3],
    radii: &[f32],
    heavy: &[bool],
    model: ExposureModel,
) -> (Vec<u32>, Vec<f32>) {
    assert!(engine.set_exposure(Some((model, heavy))), "model on device");
    let atoms = AtomSet {
        positions,
        radii,
        colours: None,
    };
    let p = SurfaceParams {
        spacing: 2.0,
        ..Default::default()
    };
    engine.compute(&atoms, &p).expect("GPU surface");
    let counts = engine.read_exposure_counts().expect("counts");
    let out = engine.read_radii().expect("radii");
    (counts, out)
}

/// Asserts the device's counts and radii equal the host's, bit for bit; returns the counts.
fn assert_same_as_host(
    what: &str,
    engine: &mut GpuEngine,
    positions: &[Vec3],
    radii: &[f32],
    heavy: &[bool],
    model: ExposureModel,
) -> Vec<u32> {
    let (counts, out) = device_exposure(engine, positions, radii, heavy, model);
    let host = heavy_neighbour_counts(positions, heavy, model.radius, model.saturation());
    let first_bad = counts.iter().zip(&host).position(|(g, h)| g != h);
    assert!(
        first_bad.is_none() && counts.len() == host.len(),
        "{what}: atom {first_bad:?}: GPU count {:?} vs host {:?} ({} atoms)",
        first_bad.map(|i| counts[i]),
        first_bad.map(|i| host[i]),
        host.len()
    );
    let host_radii = model.apply(radii, positions, heavy);
    let bits = |r: &[f32]| r.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let first_bad = (out.iter().zip(&host_radii)).position(|(g, h)| g.to_bits() != h.to_bits());
    assert!(
        first_bad.is_none() && bits(&out) == bits(&host_radii),
        "{what}: atom {first_bad:?}: GPU radius {:?} vs host {:?}",
        first_bad.map(|i| out[i]),
        first_bad.map(|i| host_radii[i])
    );
    counts
}

/// The SES preset's particles of every atom of `frame`.
fn ses_particles(topology: &Topology, frame: &Frame) -> Particles {
    let options = RadiusSet::Ses.particle_options(ParticleOptions::default());
    Particles::new(topology, frame, &options).expect("particles")
}

/// `frame` with its positions spread `factor` times about their centre (more exposed atoms).
fn spread(frame: &Frame, factor: f32) -> Frame {
    let centre = frame.positions.iter().copied().sum::<Vec3>() / frame.positions.len() as f32;
    let mut out = frame.clone();
    for p in &mut out.positions {
        *p = centre + (*p - centre) * factor;
    }
    out
}

#[test]
fn device_counts_and_radii_equal_the_hosts_on_1hpv_and_a_frame_of_adk_in_water() {
    let Some(mut engine) = engine() else { return };
    // 1hpv as it is (every atom has the saturation's 160 heavy atoms within 16 Å) and spread
    // 2 times (fewer), and adk in water (dense: counts stop at the saturation).
    let systems = [
        ("1hpv", data("1hpv.pdb"), None, 0, 1.0),
        ("1hpv spread 2 times", data("1hpv.pdb"), None, 0, 2.0),
        (
            "adk in water, frame 3",
            data("adk_oplsaa.gro"),
            Some(data("adk_oplsaa.xtc")),
            3,
            1.0,
        ),
    ];
    let (mut all, mut hydrogens) = (Vec::new(), 0);
    for (what, top, traj, index, factor) in systems {
        let t = mdsurf::io::open(&top, traj.as_deref()).expect(what);
        let frame = spread(&t.read_frame(index).expect("frame"), factor);
        let particles = ses_particles(t.topology(), &frame);
        let (model, heavy) = particles.exposure().expect("SES radii follow exposure");
        let positions = particles.positions(&frame).expect("positions");
        let counts = assert_same_as_host(
            what,
            &mut engine,
            &positions,
            particles.radii(),
            heavy,
            model,
        );
        hydrogens += heavy.iter().filter(|h| !**h).count();
        all.extend(counts);
    }
    // Hydrogens (placed, never counted) and both sides of the saturation occur.
    assert!(hydrogens > 1000, "{hydrogens} hydrogens");
    let cap = RadiusSet::Ses.exposure().expect("model").saturation();
    let below = all.iter().filter(|&&n| n < cap / 2).count();
    let at = all.iter().filter(|&&n| n == cap).count();
    assert!(
        below > 100 && at > 100,
        "{below} below {cap} / 2, {at} at it"
    );
}

/// A model whose saturation no count below reaches, so the counts are compared uncapped.
const WIDE_16: ExposureModel = ExposureModel {
    radius: 16.0,
    terms: &[(5000.0, -0.5)],
};
/// The same with a radius whose square is rounded in f32.
const WIDE_10_3: ExposureModel = ExposureModel {
    radius: 10.3,
    terms: &[(5000.0, -0.5)],
};

/// Heavy atoms placed on a sphere of the counting radius about a centre, each moved by -4 to +4
/// ulps of its distance, so that the f32 squared distances straddle r² (some equal to it): the
/// device decides every borderline atom as the host does (its count equals the host's and a
/// brute-force count of glam's `distance_squared <= r²`).
#[test]
fn atoms_within_an_ulp_of_the_radius_are_counted_as_on_the_host() {
    let Some(mut engine) = engine() else { return };
    for model in [WIDE_16, WIDE_10_3] {
        let r = model.radius;
        let r2 = r * r;
        let centre = Vec3::new(3.1, -7.7, 12.9);
        let mut positions = vec![centre];
        // Along the axes, exactly at the radius and one ulp either side.
        for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X] {
            for d in [r.next_down(), r, r.next_up()] {
                positions.push(centre + axis * d);
            }
        }
        // Fibonacci directions, each at the radius scaled by 1 + k * 2^-24.
        let n = 150;
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let s = (1.0 - z * z).sqrt();
            let dir = Vec3::new(
                s * (golden * i as f32).cos(),
                s * (golden * i as f32).sin(),
                z,
            );
            for k in -4..=4 {
                positions.push(centre + dir * (r * (1.0 + k as f32 * f32::EPSILON / 2.0)));
            }
        }
        // Every fifth atom (not the centre) is a hydrogen: placed, but never counted.
        let heavy: Vec<bool> = (0..positions.len()).map(|i| i % 5 != 1).collect();
        let radii = vec![1.5; positions.len()];
        let d2: Vec<f32> = positions
            .iter()
            .map(|q| q.distance_squared(centre))
            .collect();
        let on = d2.iter().filter(|&&d| d == r2).count();
        let just_in = d2
            .iter()
            .filter(|&&d| d < r2 && d >= r2.next_down())
            .count();
        let just_out = d2.iter().filter(|&&d| d > r2 && d <= r2.next_up()).count();
        assert!(
            on > 0 && just_in > 0 && just_out > 0,
            "radius {r}: {on} on, {just_in} an ulp in, {just_out} an ulp out"
        );
        let what = format!("sphere of radius {r}");
        let counts = assert_same_as_host(&what, &mut engine, &positions, &radii, &heavy, model);
        let brute = (positions.iter().zip(&heavy))
            .filter(|&(q, &h)| h && q.distance_squared(centre) <= r2)
            .count() as u32;
        assert_eq!(counts[0], brute, "{what}: centre");
        assert!(counts[0] > 100 && (counts[0] as usize) < positions.len() - 10);
    }
}

/// 1hpv's SES preset surface (refined, H = 1 Å) with the exposure counted on the device: its
/// radii are the host's to the bit and its area and volume the host-radii engine's (within the
/// CPU/GPU parity tolerance: its grid is sized for the largest radius the model allows, so it
/// may lie differently), in a first frame and in a second one spread 1.3 times about its
/// centre, whose smaller radii the device counts afresh.
#[test]
fn ses_surface_with_device_exposure_has_the_host_radii_surface() {
    let (Some(mut host), Some(mut device)) = (engine(), engine()) else {
        return;
    };
    let t = mdsurf::io::open(&data("1hpv.pdb"), None).expect("1hpv");
    let first = t.read_frame(0).expect("frame");
    let spread = spread(&first, 1.3);
    let particles = ses_particles(t.topology(), &first);
    let p = Preset::Ses.apply(SurfaceParams {
        spacing: 1.0,
        ..Default::default()
    });
    host.set_vertices(Preset::Ses.vertices());
    device.set_vertices(Preset::Ses.vertices());
    assert!(device.set_exposure(particles.exposure()));
    let mut areas = Vec::new();
    for frame in [&first, &spread] {
        let positions = particles.positions(frame).expect("positions");
        let frame_radii = particles.frame_radii(&positions).expect("radii follow");
        let own = AtomSet {
            positions: &positions,
            radii: particles.radii(),
            colours: None,
        };
        let a = host
            .compute(
                &AtomSet {
                    radii: &frame_radii,
                    ..own
                },
                &p,
            )
            .expect("host radii");
        let b = device.compute(&own, &p).expect("device radii");
        let bits = |r: &[f32]| r.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&device.read_radii().expect("radii")),
            bits(&frame_radii)
        );
        assert_close(&a, &b);
        areas.push(a.area);
    }
    assert!(
        (areas[1] / areas[0] - 1.3f64.powi(2)).abs() > 3.0 * tol::AREA_VOLUME_REL,
        "the spread frame's radii changed nothing: {areas:?}"
    );
}

fn assert_close(host: &SurfaceOutput, device: &SurfaceOutput) {
    for (name, a, b) in [
        ("area", host.area, device.area),
        ("volume", host.volume, device.volume),
    ] {
        assert!(
            tol::rel_close(a, b, tol::AREA_VOLUME_REL),
            "{name}: host radii {a} vs device {b}"
        );
    }
}

/// The scene engine on the GPU leaves an SES surface's exposure to its engine (the particles
/// keep their own radii: no host pass) and gives the area of the host-radii path; with
/// cavities on, which need the frame's radii, it computes them on the host as before.
#[test]
fn the_gpu_scene_counts_ses_exposure_on_the_device_unless_the_host_needs_the_radii() {
    let (Some(gpu), Some(mut reference)) = (engine(), engine()) else {
        return;
    };
    let t = mdsurf::io::open(&data("1hpv.pdb"), None).expect("1hpv");
    let topology = t.topology();
    let frame = Arc::new(spread(&t.read_frame(0).expect("frame"), 1.3));
    let mut rep = Representation {
        radii: Preset::Ses.radius_set(),
        vertices: VertexMode::Refined,
        ..Representation::new("ses", "protein and chain A", RepStyle::Surface)
    };
    rep.set_params(&Preset::Ses.apply(SurfaceParams {
        spacing: 1.0,
        ..Default::default()
    }));
    let mut layer = Layer::new(rep.clone(), topology, &RadiusOverrides::default()).expect("layer");
    let lf = layer.frame(topology, &frame).expect("host radii");
    let own = lf.particles.radii().to_vec();
    let frame_radii = lf.frame_radii.clone().expect("radii follow exposure");
    assert!(own != frame_radii, "chain A spread: no radius changed");
    reference.set_vertices(VertexMode::Refined);
    let expected = reference
        .compute(&lf.atom_set(), &rep.params())
        .expect("host radii");
    let mut scene = SceneEngine::new(SceneBackend::Gpu(Box::new(gpu)));
    for cavities in [false, true] {
        let request = RepRequest {
            id: 1,
            rep: Representation {
                cavities,
                ..rep.clone()
            },
        };
        let out = scene
            .frame(topology, 0, &frame, &[request])
            .expect("scene frame");
        let layer = &out.layers[0];
        let radii = layer.particles.radii.as_slice();
        // (Compared without printing thousands of radii.)
        if cavities {
            assert!(
                radii == frame_radii.as_slice(),
                "cavities: not the host radii"
            );
        } else {
            assert!(
                radii == own.as_slice(),
                "device exposure: not the own radii"
            );
        }
        assert_close(&expected, &layer.output);
    }
}

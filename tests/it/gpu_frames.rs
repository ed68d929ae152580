//! The GPU engine over several frames and under stress: a jittered multi-frame trajectory,
//! slider changes that re-run only what they affect (I: Marching Cubes; colours: the colour
//! pass), a grid forced through slabs (same mesh as one pass), a mesh forced to overflow (flag,
//! no draw, grow, rerun), very uneven bins (a dense cluster plus far-away atoms), and engines
//! built on several threads at once; per-atom arrays written in parallel pieces.

use crate::gpu_support::*;
use glam::Vec3;
use mdsurf::gpu::engine::EngineOptions;
use mdsurf::gpu::frame::Work;
use mdsurf::gpu::output::{read_bytes, read_pod};
use mdsurf::gpu::{Changes, DrawIndexedArgs, GpuEngine};
use mdsurf::surface::{SurfaceEngine, SurfaceParams};

fn cluster(n: usize, seed: u64, extent: f32) -> Atoms {
    let base = Atoms {
        positions: vec![Vec3::ZERO; n],
        radii: (0..n).map(|i| [1.0, 1.5, 1.4, 1.3, 1.9][i % 5]).collect(),
        colours: Some(
            (0..n)
                .map(|i| [(i % 3) as f32 / 2.0, 0.5, 1.0 - (i % 7) as f32 / 6.0])
                .collect(),
        ),
    };
    jitter(&base, seed, extent)
}

fn compare(
    engine: &mut GpuEngine,
    what: &str,
    atoms: &Atoms,
    p: &SurfaceParams,
) -> mdsurf::surface::Mesh {
    let out = engine
        .compute(&atoms.set(), p)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let (_, _, cpu) = reference(atoms, p);
    assert_mesh_close(what, &out.mesh, &cpu, out.area, out.volume);
    assert!(out.mesh.is_closed(), "{what}: mesh not closed");
    out.mesh
}

#[test]
fn multi_frame_trajectory() {
    let Some(mut engine) = engine() else { return };
    let first = cluster(150, 7, 9.0);
    let p = SurfaceParams {
        spacing: 0.8,
        ..Default::default()
    };
    for frame in 0..4u64 {
        let atoms = jitter(&first, 100 + frame, 0.6);
        compare(&mut engine, &format!("frame {frame}"), &atoms, &p);
        assert_eq!(engine.last_frame().map(|f| f.work), Some(Work::Full));
    }
}

#[test]
fn slider_changes_rerun_only_what_they_affect() {
    let Some(mut engine) = engine() else { return };
    let mut atoms = cluster(80, 3, 6.0);
    let p = SurfaceParams {
        spacing: 0.7,
        ..Default::default()
    };
    let before = compare(&mut engine, "start", &atoms, &p);

    let p_iso = SurfaceParams { isovalue: 0.8, ..p };
    compare(&mut engine, "I = 0.8", &atoms, &p_iso);
    assert_eq!(engine.last_frame().map(|f| f.work), Some(Work::Mc));

    let back = compare(&mut engine, "I back to 0.5", &atoms, &p);
    assert_eq!(engine.last_frame().map(|f| f.work), Some(Work::Mc));
    assert_eq!(
        back, before,
        "returning to I = 0.5 must give the very same mesh"
    );

    atoms.colours = Some(vec![[0.1, 0.9, 0.2]; atoms.positions.len()]);
    let recoloured = compare(&mut engine, "new colours", &atoms, &p);
    assert_eq!(engine.last_frame().map(|f| f.work), Some(Work::Colour));
    assert!(
        recoloured.positions == before.positions,
        "a colour change moved vertices"
    );
    assert!(
        recoloured.indices == before.indices,
        "a colour change changed triangles"
    );

    let p_h = SurfaceParams { spacing: 0.6, ..p };
    compare(&mut engine, "H = 0.6", &atoms, &p_h);
    assert_eq!(engine.last_frame().map(|f| f.work), Some(Work::Full));
}

#[test]
fn slabs_give_the_one_pass_mesh() {
    let Some(mut one) = engine() else { return };
    let Some(mut slabbed) = engine() else { return };
    let opts = EngineOptions {
        max_slab_layers: Some(3),
        ..slabbed.options()
    };
    slabbed.set_options(opts);
    let atoms = load_pdb("1hpv.pdb");
    let p = SurfaceParams {
        spacing: 2.0,
        ..Default::default()
    };
    let a = one.compute(&atoms.set(), &p).expect("one pass");
    let b = slabbed.compute(&atoms.set(), &p).expect("slabs");
    let slabs = slabbed.last_frame().map(|f| f.slabs).unwrap_or(0);
    assert!(slabs >= 5, "only {slabs} slabs");
    assert_eq!(one.last_frame().map(|f| f.slabs), Some(1));
    assert!(a.mesh.indices == b.mesh.indices, "slabbed triangles differ");
    assert_eq!(a.mesh.vertex_count(), b.mesh.vertex_count());
    for (v, (x, y)) in a.mesh.positions.iter().zip(&b.mesh.positions).enumerate() {
        assert!((*x - *y).length() < 1e-4, "vertex {v}: {x} vs {y}");
    }
    for (v, (x, y)) in a.mesh.colours.iter().zip(&b.mesh.colours).enumerate() {
        assert!(
            mdsurf::gpu::tolerance::colour_close(*x, *y),
            "vertex {v} colour"
        );
    }
    let (_, _, cpu) = reference(&atoms, &p);
    assert_mesh_close("slabs", &b.mesh, &cpu, b.area, b.volume);
}

#[test]
fn overflow_is_flagged_then_grown() {
    let Some(mut engine) = engine() else { return };
    let opts = EngineOptions {
        initial_mesh_capacity: Some((32, 32)),
        ..engine.options()
    };
    engine.set_options(opts);
    let atoms = cluster(60, 11, 5.0);
    let p = SurfaceParams {
        spacing: 0.6,
        ..Default::default()
    };
    // Non-blocking path: the frame overflows, draws nothing, and says so.
    let info = engine
        .submit(&atoms.set(), &p, Changes::ALL)
        .expect("submit");
    let stats = loop {
        engine.context().wait().expect("wait");
        if let Some(s) = engine.poll_stats().expect("poll") {
            break s;
        }
    };
    assert_eq!(stats.frame, info.frame);
    assert!(stats.overflow, "a 32-triangle buffer must overflow");
    assert!(stats.triangle_count > 32);
    let ctx = engine.context().clone();
    let args: Vec<DrawIndexedArgs> =
        read_pod(&ctx.device, &ctx.queue, &engine.surface().draw_args, 1).expect("args");
    assert_eq!(
        args[0].index_count, 0,
        "an overflowed frame must not be drawn"
    );
    // The next frame has grown buffers.
    engine
        .submit(&atoms.set(), &p, Changes::default())
        .expect("submit");
    engine.context().wait().expect("wait");
    let next = engine.poll_stats().expect("poll").expect("stats");
    assert!(!next.overflow);
    let args: Vec<DrawIndexedArgs> =
        read_pod(&ctx.device, &ctx.queue, &engine.surface().draw_args, 1).expect("args");
    assert_eq!(args[0].index_count, 3 * next.triangle_count);
    // The blocking path grows and reruns by itself.
    let mut fresh = GpuEngine::with_context(ctx).expect("engine");
    fresh.set_options(opts);
    compare(&mut fresh, "overflowed then rerun", &atoms, &p);
}

#[test]
fn very_uneven_bins() {
    let Some(mut engine) = engine() else { return };
    let mut atoms = cluster(400, 5, 2.5);
    for (i, far) in [
        Vec3::new(40.0, 0.0, 0.0),
        Vec3::new(0.0, -35.0, 10.0),
        Vec3::new(-30.0, 25.0, -30.0),
    ]
    .into_iter()
    .enumerate()
    {
        atoms.positions.push(far);
        atoms.radii.push(1.2 + 0.3 * i as f32);
        if let Some(c) = atoms.colours.as_mut() {
            c.push([1.0, 0.0, 0.0]);
        }
    }
    let p = SurfaceParams {
        spacing: 1.0,
        ..Default::default()
    };
    let mesh = compare(&mut engine, "dense cluster + far atoms", &atoms, &p);
    assert!(
        mesh.euler_characteristic() >= 8,
        "expected 4+ separate components"
    );
}

#[test]
fn same_surface_whatever_the_path_or_atom_order() {
    let Some(mut engine) = engine() else { return };
    let atoms = cluster(120, 21, 5.0);
    let p = SurfaceParams {
        spacing: 0.6,
        ..Default::default()
    };
    let first = engine.compute(&atoms.set(), &p).expect("first");
    // Round trip through another H (density re-runs twice, binning too).
    engine
        .compute(&atoms.set(), &SurfaceParams { spacing: 0.5, ..p })
        .expect("H = 0.5");
    let again = engine.compute(&atoms.set(), &p).expect("back");
    assert_eq!(engine.last_frame().map(|f| f.work), Some(Work::Full));
    assert!(again.mesh == first.mesh, "H round trip changed the mesh");
    // Reversed atom order on a fresh engine: the very same mesh, bit for bit.
    let reversed = Atoms {
        positions: atoms.positions.iter().rev().copied().collect(),
        radii: atoms.radii.iter().rev().copied().collect(),
        colours: atoms
            .colours
            .as_ref()
            .map(|c| c.iter().rev().copied().collect()),
    };
    let Some(mut other) = crate::gpu_support::engine() else {
        return;
    };
    let rev = other.compute(&reversed.set(), &p).expect("reversed");
    assert!(rev.mesh == first.mesh, "atom order changed the mesh");
}

/// A device on the test adapter with the WebGPU default limits (the adapter's texture and
/// buffer sizes) as `adjust` changes them; `None` (test skipped) only without `REQUIRE_GPU=1`.
fn device_with(
    adjust: impl Fn(wgpu::Limits) -> wgpu::Limits,
) -> Option<(wgpu::Device, wgpu::Queue)> {
    let ctx = mdsurf::gpu::GpuContext::headless_or_skip().expect("REQUIRE_GPU=1 but no adapter")?;
    let limits = adjust(wgpu::Limits::default().using_resolution(ctx.limits.clone()));
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&Default::default())).expect("adapter");
    let device = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: limits,
        ..Default::default()
    }));
    Some(device.expect("device with the asked-for limits"))
}

#[test]
fn runs_on_a_device_with_webgpu_default_limits() {
    // The viewer shares eframe's device, which may have only the WebGPU default limits
    // (8 storage buffers per stage, 128 MiB bindings): every pipeline must still build.
    let Some((device, queue)) = device_with(|limits| limits) else {
        return;
    };
    let mut engine = GpuEngine::try_from_device(device, queue).expect("engine on default limits");
    compare(
        &mut engine,
        "default limits",
        &cluster(40, 9, 4.0),
        &SurfaceParams {
            spacing: 0.7,
            ..Default::default()
        },
    );
}

/// A device below the engine's widest layout (Mesa 21.2's lavapipe, Ubuntu 20.04's, allows 3
/// storage buffers per stage): the engine says so in one line with both numbers, instead of
/// wgpu's validation error for the first layout that did not fit. With the default limits the
/// widest layout fits (the test above runs frames there).
#[test]
fn a_device_with_too_few_storage_buffers_is_refused_in_plain_words() {
    let Some((device, queue)) = device_with(|limits| wgpu::Limits {
        max_storage_buffers_per_shader_stage: 3,
        ..limits
    }) else {
        return;
    };
    let err = GpuEngine::try_from_device(device, queue).expect_err("3 storage buffers are too few");
    let text = err.to_string();
    assert!(
        matches!(
            err,
            mdsurf::gpu::GpuError::TooFewStorageBuffers { needed, allowed: 3 }
                if needed > 3 && needed <= wgpu::Limits::default().max_storage_buffers_per_shader_stage
        ),
        "{text}"
    );
    assert!(!text.contains("Validation"), "{text}");
}

#[test]
fn a_failed_frame_does_not_leave_stale_atoms_behind() {
    let Some(mut engine) = engine() else { return };
    let a = cluster(50, 1, 4.0);
    let p = SurfaceParams {
        spacing: 0.7,
        ..Default::default()
    };
    engine.compute(&a.set(), &p).expect("first");
    let b = jitter(&a, 2, 1.0);
    let bad = SurfaceParams {
        isovalue: -1.0,
        ..p
    };
    assert!(
        engine.compute(&b.set(), &bad).is_err(),
        "negative isovalue must fail"
    );
    // Same atoms again with good parameters: they must be uploaded, not taken as unchanged.
    compare(&mut engine, "after a failed frame", &b, &p);
}

/// Engines built and run on several threads at once, each on its own device (as the parallel
/// tests do, or a headless export beside the viewer), all finish with the same mesh. NVIDIA's
/// Vulkan driver deadlocked when threads compiled pipelines concurrently, until
/// `gpu::context::compile_lock` serialised shader compilation across the process.
#[test]
fn engines_built_on_several_threads_at_once_agree() {
    if context().is_none() {
        return;
    }
    let atoms = cluster(60, 11, 5.0);
    let p = SurfaceParams {
        spacing: 0.8,
        ..Default::default()
    };
    let meshes: Vec<_> = std::thread::scope(|s| {
        let threads: Vec<_> = (0..4)
            .map(|_| {
                s.spawn(|| {
                    let mut engine = engine().expect("GPU engine");
                    engine.compute(&atoms.set(), &p).expect("GPU frame").mesh
                })
            })
            .collect();
        threads
            .into_iter()
            .map(|t| t.join().expect("engine thread"))
            .collect()
    });
    assert!(meshes[0].triangle_count() > 100, "a surface of 60 atoms");
    for (i, mesh) in meshes.iter().enumerate().skip(1) {
        assert_eq!(mesh.indices, meshes[0].indices, "thread {i}: triangles");
        assert_eq!(mesh.positions, meshes[0].positions, "thread {i}: vertices");
    }
}

/// Per-atom arrays are copied into wgpu's staging memory in pieces on every core
/// (`gpu::inputs::write_in_pieces`): the buffer reads back byte for byte what was written,
/// for pieces that divide it unevenly and for pieces as large as the whole.
#[test]
fn arrays_written_in_parallel_pieces_read_back_exactly() {
    let Some(ctx) = context() else { return };
    let bytes: Vec<u8> = (0..1_000_003u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    let size = bytes.len().next_multiple_of(4);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("pieces"),
        size: size as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut padded = bytes.clone();
    padded.resize(size, 0);
    for piece in [4096, 65_537, 1 << 20] {
        mdsurf::gpu::inputs::write_in_pieces(&ctx.queue, &buffer, &padded, piece);
        let back = read_bytes(&ctx.device, &ctx.queue, &buffer, 0, size as u64).expect("readback");
        assert_eq!(back.len(), size, "piece {piece}");
        let first_bad = back.iter().zip(&padded).position(|(a, b)| a != b);
        assert_eq!(first_bad, None, "piece {piece}: first differing byte");
        // Clear it so the next piece size cannot pass on this one's bytes.
        ctx.queue.write_buffer(&buffer, 0, &vec![0u8; size]);
    }
}

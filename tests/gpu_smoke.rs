mod gpu_support;
use glam::Vec3;
use gpu_support::*;
use mdsurf::surface::{SurfaceEngine, SurfaceParams};

#[test]
fn one_atom_smoke() {
    let Some(mut engine) = engine() else { return };
    eprintln!("{engine:?} ts={}", engine.context().timestamps);
    let atoms = Atoms {
        positions: vec![Vec3::new(1.0, 2.0, 3.0)],
        radii: vec![1.5],
        colours: Some(vec![[1.0, 0.5, 0.25]]),
    };
    let p = SurfaceParams {
        spacing: 0.4,
        ..Default::default()
    };
    let out = engine.compute(&atoms.set(), &p).unwrap();
    let (_, _, cpu) = reference(&atoms, &p);
    eprintln!(
        "gpu tris {} verts {} area {} vol {} | cpu tris {} verts {} area {} vol {}",
        out.mesh.triangle_count(),
        out.mesh.vertex_count(),
        out.area,
        out.volume,
        cpu.triangle_count(),
        cpu.vertex_count(),
        cpu.area(),
        cpu.volume()
    );
    eprintln!("{:?}", out.timings);
    assert_mesh_close("one atom", &out.mesh, &cpu, out.area, out.volume);
}

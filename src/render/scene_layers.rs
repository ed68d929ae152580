//! From a computed scene frame ([`crate::scene::SceneFrame`]) to what the renderer draws: one
//! surface layer per surface representation (GPU buffers drawn in place, or a host mesh
//! uploaded) with its opacity, the cavities of a surface whose `cavities` switch is on as one
//! more, opaque layer, each cavity in its id's colour (per vertex, see
//! [`crate::scene::cavity_layer`]), and the atoms of
//! every atom representation in one instance list.
//! The window ([`crate::app::view_renderer`]) and `mdsurf render` both go through
//! [`GpuScene::show_layers`], so a frame looks the same in either.

use crate::scene::LayerResult;
use crate::scene::representation::Representation;

use super::atoms::atom_instances;
use super::scene::GpuScene;
use super::settings::RenderSettings;

impl GpuScene {
    /// Shows `layers` (each computed result with the representation it is drawn as now: its
    /// opacity may have changed since it was computed), replacing what was shown. Atom styles
    /// take the sphere and bond sizes of `look`.
    pub fn show_layers<'a>(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layers: impl IntoIterator<Item = (&'a LayerResult, &'a Representation)>,
        look: &RenderSettings,
    ) {
        let mut k = 0;
        let mut spheres = Vec::new();
        let mut cylinders = Vec::new();
        for (layer, rep) in layers {
            if let Some(style) = rep.style.atom_style() {
                let look = RenderSettings {
                    atom_style: style,
                    ..*look
                };
                let p = &layer.particles;
                let (s, c) =
                    atom_instances(&p.positions, &p.radii, Some(&p.colours), &p.bonds, &look);
                spheres.extend(s);
                cylinders.extend(c);
                continue;
            }
            match &layer.gpu_surface {
                Some(g) => {
                    let grid = &layer.output.grid;
                    let far = glam::UVec3::from(grid.dims).saturating_sub(glam::UVec3::ONE);
                    let hi = grid.origin + far.as_vec3() * grid.spacing;
                    self.set_layer_gpu_surface(k, g.clone(), Some((grid.origin, hi)));
                }
                None => {
                    self.set_layer_mesh(k, device, queue, &layer.output.mesh);
                    self.layer_mut(k).closed = layer.closed;
                }
            }
            let surface = self.layer_mut(k);
            surface.opacity = Some(rep.opacity);
            surface.colour = None;
            k += 1;
            // Its cavities, opaque (seen through the surface when that is see-through), hidden
            // with the surface when it is faded out.
            let walls = layer.cavities.as_ref().map(|c| &c.mesh);
            if let Some(walls) = walls.filter(|m| rep.cavities && !m.indices.is_empty()) {
                self.set_layer_mesh(k, device, queue, walls);
                let cavity = self.layer_mut(k);
                cavity.opacity = Some(if rep.opacity > 0.0 { 1.0 } else { 0.0 });
                // The walls' own colours: each cavity's id's.
                cavity.colour = None;
                k += 1;
            }
        }
        self.set_surface_count(k);
        self.set_atoms(device, queue, &spheres, &cylinders);
    }
}

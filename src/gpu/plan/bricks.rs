//! Sparse bricks: the slots a frame's reached bricks take, how many to hold (grown from the
//! reached count, capped by the binding limit), where class entries live, and the CPU-side count
//! of reached bricks per layer from a slot table.

use super::*;

/// Samples per sparse brick ([`BRICK`]^3).
pub const BRICK_SAMPLES: u64 = (BRICK * BRICK * BRICK) as u64;

/// Class entries per brick slot on sparse classes, (`BRICK` + 1)^3 (`CLASS_APRON`^3 in
/// `shaders/brick_const.wgsl`, used by `shaders/class_entries.wgsl`):
/// a reached brick holds its own points' class words and vertex bases, and the points just below
/// it in unreached bricks, whose cells reach into it.
pub const CLASS_ENTRIES_PER_SLOT: u64 = ((BRICK + 1) * (BRICK + 1) * (BRICK + 1)) as u64;

/// The class entries (class words and vertex bases) one slab needs and whether they are held
/// per brick slot (`sparse`): on sparse bricks with `brick_slots` slots, per slot when that
/// takes fewer entries than one per classified point ([`FramePlan::class_points`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClassEntries {
    /// Entries of the class-word and vertex-base buffers (the active-cell list holds as many).
    pub entries: u64,
    /// Held per brick slot.
    pub sparse: bool,
}

impl ClassEntries {
    /// The layout for `plan` with `brick_slots` (None: dense volumes).
    pub fn for_plan(plan: &FramePlan, brick_slots: Option<u64>) -> ClassEntries {
        let points = plan.class_points();
        match brick_slots {
            Some(slots) if slots * CLASS_ENTRIES_PER_SLOT < points => ClassEntries {
                entries: slots * CLASS_ENTRIES_PER_SLOT,
                sparse: true,
            },
            _ => ClassEntries {
                entries: points,
                sparse: false,
            },
        }
    }
}

/// The most brick slots the largest binding allows (the colour slots, 12 bytes per sample,
/// and the density table plus slots).
pub fn brick_slot_limit(plan: &FramePlan, max_binding: u64) -> u64 {
    let roomy: u64 = plan.brick_dims.iter().map(|&d| d as u64 + 1).product();
    let by_colour = max_binding / (12 * BRICK_SAMPLES);
    let by_density = (max_binding / 4).saturating_sub(roomy) / BRICK_SAMPLES;
    by_colour.min(by_density).max(1)
}

/// The brick slots the buffers grow to when a frame's slabs needed `slots` (the most reached
/// bricks of one slab) and the buffers held `capacity` slots (None when they suffice): the
/// need with an eighth to spare, rounded up to a multiple of 64 bricks, within
/// [`brick_slot_limit`].
pub fn grown_brick_want(
    plan: &FramePlan,
    slots: u64,
    capacity: u64,
    max_binding: u64,
) -> Option<u64> {
    let need = slots.min(plan.max_slab_bricks());
    (need > capacity).then(|| {
        (need + need / 8)
            .next_multiple_of(64)
            .min(brick_slot_limit(plan, max_binding))
    })
}

/// The brick slots a fresh engine settles at for a frame on `plan` whose slabs need `slots`
/// (the most reached bricks of one slab: [`ReachedBricks::slab_need`]). Its first sparse
/// frame counts the reached bricks before density runs (a brick pass, read back once), so the
/// slots are sized from that count as [`grown_brick_want`] grows them, and density runs once.
pub fn settled_brick_slots(plan: &FramePlan, slots: u64, max_binding: u64) -> u64 {
    grown_brick_want(plan, slots.max(1), 0, max_binding).unwrap_or(1)
}

/// The most brick slots the engine can hold on `plan`: grown for a slab whose every brick is
/// reached.
pub fn largest_brick_slots(plan: &FramePlan, max_binding: u64) -> u64 {
    settled_brick_slots(plan, plan.max_slab_bricks(), max_binding)
}

/// The brick slot table the sparse-brick pass writes into the first words of the density
/// buffer (`shaders/bricks.wgsl`), read on the host: per brick its slot (the exclusive scan of
/// the reached flags), with [`SlotTable::UNREACHED`] set when no atom reaches it.
#[derive(Debug, Clone, Copy)]
pub struct SlotTable<'a> {
    plan: &'a FramePlan,
    words: &'a [u32],
}

impl<'a> SlotTable<'a> {
    /// The bit set on an unreached brick's word (`SLOT_UNREACHED` in `shaders/brick_const.wgsl`).
    pub const UNREACHED: u32 = 1 << 31;

    /// The table of `plan` in `words` (its first [`FramePlan::brick_count`] words are read).
    pub fn new(plan: &'a FramePlan, words: &'a [u32]) -> SlotTable<'a> {
        SlotTable { plan, words }
    }

    /// The slot of brick `b` (brick coordinates), None when no atom reaches it (or it lies
    /// outside the table).
    pub fn slot(&self, b: [u32; 3]) -> Option<u32> {
        let [bx, by, bz] = self.plan.brick_dims;
        if b[0] >= bx || b[1] >= by || b[2] >= bz {
            return None;
        }
        let t = *self.words.get((b[0] + bx * (b[1] + by * b[2])) as usize)?;
        (t & Self::UNREACHED == 0).then_some(t)
    }

    /// The slot the slots of `slab` count from: that of its first density brick layer (the
    /// reached bricks before it, for an unreached brick too).
    pub fn first_slot(&self, slab: &Slab) -> u32 {
        let [bx, by, _] = self.plan.brick_dims;
        let at = ((slab.dens_z0 / BRICK) * bx * by) as usize;
        self.words.get(at).copied().unwrap_or(0) & !Self::UNREACHED
    }

    /// Reached bricks per brick layer (z), bottom to top.
    pub fn reached(&self) -> ReachedBricks {
        let [bx, by, bz] = self.plan.brick_dims;
        let layer = (bx * by).max(1) as usize;
        ReachedBricks {
            layers: self
                .words
                .chunks(layer)
                .take(bz as usize)
                .map(|l| l.iter().filter(|&&t| t & Self::UNREACHED == 0).count() as u64)
                .collect(),
        }
    }
}

/// Reached sparse bricks per brick layer (z), counted on the host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReachedBricks {
    /// Reached bricks of each brick layer, bottom to top.
    pub layers: Vec<u64>,
}

impl ReachedBricks {
    /// All reached bricks ([`crate::gpu::output::FrameStats::reached_bricks`]).
    pub fn total(&self) -> u64 {
        self.layers.iter().sum()
    }

    /// The most reached bricks the density layers of one slab of `plan` touch: the brick
    /// slots the frame needs ([`crate::gpu::output::FrameStats::brick_slots`]).
    pub fn slab_need(&self, plan: &FramePlan) -> u64 {
        plan.slabs
            .iter()
            .map(|s| {
                let bz0 = (s.dens_z0 / BRICK) as usize;
                let bz1 = ((s.dens_z0 + s.dens_layers.max(1) - 1) / BRICK) as usize;
                self.layers[bz0..=bz1.min(self.layers.len() - 1)]
                    .iter()
                    .sum::<u64>()
            })
            .max()
            .unwrap_or(0)
    }
}

/// The bricks `shaders/bricks.wgsl` marks as reached for atoms at `positions` (Å) of radii
/// `radii` (Å) on `plan`, counted on the host with the shader's f32 arithmetic (`mark`: the
/// atoms of the bin cells around each brick, the same slack), per brick layer: what the
/// engine's counters report, so the brick slots are known without a device.
pub fn count_reached_bricks(
    plan: &FramePlan,
    positions: &[glam::Vec3],
    radii: &[f32],
    radius_scale: f32,
    cutoff: f32,
) -> ReachedBricks {
    let g = &plan.grid;
    let o = g.origin;
    let cd = plan.cell_dims;
    let cell_coord = |x: f32, o: f32, n: u32| -> u32 {
        (((x - o) / plan.cell_size).floor() as i32).clamp(0, n as i32 - 1) as u32
    };
    let cell_index = |c: [u32; 3]| (c[0] + cd[0] * (c[1] + cd[1] * c[2])) as usize;
    let mut cells: Vec<Vec<(glam::Vec3, f32)>> = vec![Vec::new(); plan.cell_count() as usize];
    for (p, &r) in positions.iter().zip(radii) {
        let c = [
            cell_coord(p.x, o.x, cd[0]),
            cell_coord(p.y, o.y, cd[1]),
            cell_coord(p.z, o.z, cd[2]),
        ];
        cells[cell_index(c)].push((*p, r * radius_scale));
    }
    let reach = plan.max_cut * 1.0001 + 1e-4;
    let [bx, by, bz] = plan.brick_dims;
    let mut reached = vec![0; bz as usize];
    for k in 0..bz {
        for j in 0..by {
            for i in 0..bx {
                let corner = |add: u32| {
                    glam::Vec3::new(
                        o.x + g.spacing * (i * BRICK + add) as f32,
                        o.y + g.spacing * (j * BRICK + add) as f32,
                        o.z + g.spacing * (k * BRICK + add) as f32,
                    )
                };
                let (lo, hi) = (corner(0), corner(BRICK - 1));
                let c0 = [
                    cell_coord(lo.x - reach, o.x, cd[0]),
                    cell_coord(lo.y - reach, o.y, cd[1]),
                    cell_coord(lo.z - reach, o.z, cd[2]),
                ];
                let c1 = [
                    cell_coord(hi.x + reach, o.x, cd[0]),
                    cell_coord(hi.y + reach, o.y, cd[1]),
                    cell_coord(hi.z + reach, o.z, cd[2]),
                ];
                let hit = (c0[2]..=c1[2]).any(|cz| {
                    (c0[1]..=c1[1]).any(|cy| {
                        (c0[0]..=c1[0]).any(|cx| {
                            cells[cell_index([cx, cy, cz])].iter().any(|&(a, w)| {
                                let d = (lo - a).max(a - hi).max(glam::Vec3::ZERO);
                                let c = cutoff * w * 1.001 + 1e-3;
                                d.x * d.x + d.y * d.y + d.z * d.z < c * c
                            })
                        })
                    })
                });
                reached[k as usize] += u64::from(hit);
            }
        }
    }
    ReachedBricks { layers: reached }
}

//! Cavities followed from frame to frame: a cavity keeps its id while it overlaps its previous
//! self, where two cavities overlap when their centroids are within the larger of their
//! bounding radii ([`Cavity::radius`]; in a periodic cell, by the centroids' nearest images). Each previous cavity hands its id to the largest (by
//! volume) current cavity it overlaps; a current cavity handed several ids keeps the one of the
//! largest previous cavity (a merge), one handed none gets a new id (a birth, or a split when it
//! overlaps a previous cavity that chose another heir).

use super::Cavity;

/// A cavity with its track.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackedCavity {
    /// Id, stable while the cavity persists (from 1).
    pub id: u64,
    /// First frame of this id.
    pub born: usize,
    /// The cavity in the current frame.
    pub cavity: Cavity,
}

/// Something that happened to the cavities between two frames.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CavityEvent {
    /// A cavity appeared that overlaps none of the previous frame.
    Birth {
        /// Its id.
        id: u64,
    },
    /// A cavity of the previous frame overlaps none of this frame (it closed or was filled).
    Death {
        /// Its id.
        id: u64,
    },
    /// Several previous cavities became one, which keeps the id of the largest.
    Merge {
        /// Ids that ended in the merge (the kept one excluded).
        from: Vec<u64>,
        /// The id that continues.
        into: u64,
    },
    /// A previous cavity became several: it continues in its largest part, the others get
    /// new ids.
    Split {
        /// The id that continues.
        from: u64,
        /// New ids of the other parts.
        into: Vec<u64>,
    },
}

/// The result of one [`CavityTracker::update`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TrackUpdate {
    /// This frame's cavities with their ids, in the order given.
    pub cavities: Vec<TrackedCavity>,
    /// What changed since the previous frame.
    pub events: Vec<CavityEvent>,
}

/// Follows cavities over the frames of one representation (feed frames in order).
#[derive(Debug, Clone, Default)]
pub struct CavityTracker {
    previous: Vec<TrackedCavity>,
    next_id: u64,
}

/// True when `a` and `b` overlap (centroids within the larger bounding radius).
fn overlap(a: &Cavity, b: &Cavity) -> bool {
    a.centroid_distance(b) <= a.radius.max(b.radius)
}

impl CavityTracker {
    /// A tracker with no history.
    pub fn new() -> CavityTracker {
        CavityTracker::default()
    }

    /// The cavities of the last frame given.
    pub fn current(&self) -> &[TrackedCavity] {
        &self.previous
    }

    fn new_id(&mut self) -> u64 {
        self.next_id += 1;
        self.next_id
    }

    /// Gives the cavities of `frame` ids and reports the events since the previous call.
    pub fn update(&mut self, frame: usize, cavities: &[Cavity]) -> TrackUpdate {
        let prev = std::mem::take(&mut self.previous);
        // Each previous cavity's heir: the largest current cavity it overlaps.
        let heir: Vec<Option<usize>> = prev
            .iter()
            .map(|p| {
                (0..cavities.len())
                    .filter(|&c| overlap(&p.cavity, &cavities[c]))
                    .max_by(|&x, &y| cavities[x].volume.total_cmp(&cavities[y].volume))
            })
            .collect();
        let mut events = Vec::new();
        let mut split_parts: Vec<(usize, u64)> = Vec::new();
        let mut out = Vec::with_capacity(cavities.len());
        for (c, cavity) in cavities.iter().enumerate() {
            // Previous cavities handing their id to this one, largest first.
            let mut givers: Vec<usize> = (0..prev.len()).filter(|&p| heir[p] == Some(c)).collect();
            givers.sort_by(|&x, &y| prev[y].cavity.volume.total_cmp(&prev[x].cavity.volume));
            let (id, born) = match givers.first() {
                Some(&keep) => {
                    if givers.len() > 1 {
                        events.push(CavityEvent::Merge {
                            from: givers[1..].iter().map(|&p| prev[p].id).collect(),
                            into: prev[keep].id,
                        });
                    }
                    (prev[keep].id, prev[keep].born)
                }
                None => {
                    let id = self.new_id();
                    // Part of a previous cavity that continues elsewhere: a split.
                    match (0..prev.len()).find(|&p| overlap(&prev[p].cavity, cavity)) {
                        Some(p) => split_parts.push((p, id)),
                        None => events.push(CavityEvent::Birth { id }),
                    }
                    (id, frame)
                }
            };
            out.push(TrackedCavity {
                id,
                born,
                cavity: cavity.clone(),
            });
        }
        for (p, _) in prev.iter().enumerate() {
            let parts: Vec<u64> = split_parts
                .iter()
                .filter(|&&(q, _)| q == p)
                .map(|&(_, id)| id)
                .collect();
            if !parts.is_empty() {
                events.push(CavityEvent::Split {
                    from: prev[p].id,
                    into: parts,
                });
            }
            if heir[p].is_none() {
                events.push(CavityEvent::Death { id: prev[p].id });
            }
        }
        self.previous = out.clone();
        TrackUpdate {
            cavities: out,
            events,
        }
    }
}

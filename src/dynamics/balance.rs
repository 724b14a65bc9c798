//! What the repartition of a running deposition reads of the mechanics:
//! each whole body's current centre and its work (elements and the
//! contact pairs it found at the last detection), in the units of the
//! partition weights ([`crate::parallel::element_work`]).

use std::collections::HashMap;

use super::ExplicitDomain;
use crate::model::Model;
use crate::parallel::{element_work, Part};

/// A whole body as the repartition sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyLoad {
    /// Global body id.
    pub body: u32,
    /// Mean of its nodes' current positions (m).
    pub centre: [f64; 3],
    /// Its elements' and found pairs' work per step.
    pub work: f64,
}

impl ExplicitDomain {
    /// Collective. Detect the contact candidates at the current positions
    /// (as a restore does), so the work each rank finds is that of this
    /// moment on any run that reaches it, a restarted one too. Forces do
    /// not depend on when candidates were found.
    pub fn detect_now(
        &mut self,
        comm: &mpi::topology::SimpleCommunicator,
    ) -> crate::error::Result<()> {
        self.detect(comm)?;
        self.redetect = false;
        Ok(())
    }

    /// The work of this rank: its elements' and the pairs its tets found
    /// at the last detection (before the pairs are shared out).
    pub fn found_work(&self) -> f64 {
        self.element_work + self.body_pair_work.values().sum::<f64>()
    }

    /// The work this rank evaluates: its elements' and the pairs it took
    /// at the last detection (its share of all pairs found).
    pub fn evaluated_work(&self) -> f64 {
        self.element_work + self.pair_share
    }

    /// The whole bodies of `part` with their current centres and work.
    pub fn body_loads(&self, model: &Model, part: &Part) -> Vec<BodyLoad> {
        let mut sum: HashMap<u32, ([f64; 3], usize)> = part
            .whole_bodies
            .iter()
            .map(|&b| (b, ([0.0; 3], 0)))
            .collect();
        for (x, b) in self.x[..self.n_owned].iter().zip(&self.owned_body) {
            if let Some((s, n)) = sum.get_mut(b) {
                for d in 0..3 {
                    s[d] += x[d];
                }
                *n += 1;
            }
        }
        part.whole_bodies
            .iter()
            .map(|&b| {
                let (s, n) = sum[&b];
                let body = &model.bodies[b as usize];
                let elements = f64::from(body.elem_range.1 - body.elem_range.0);
                BodyLoad {
                    body: b,
                    centre: s.map(|v| v / n.max(1) as f64),
                    work: elements * element_work(model, b as usize)
                        + self.body_pair_work.get(&b).copied().unwrap_or(0.0),
                }
            })
            .collect()
    }
}

/// Bytes a vector of `cap` capacity holds.
fn held<T>(_: &[T], cap: usize) -> usize {
    cap * std::mem::size_of::<T>()
}

impl ExplicitDomain {
    /// What this rank's domain holds, by array (bytes, from capacities):
    /// where the memory of a run goes (`FDEM_LOG=memory=debug`).
    pub fn held_bytes(&self) -> Vec<(&'static str, usize)> {
        macro_rules! v {
            ($name:literal, $f:expr) => {
                ($name, held(&$f, $f.capacity()))
            };
        }
        vec![
            v!("node arrays x", self.x),
            v!("elements", self.elements),
            v!("stress", self.stress),
            v!("candidates", self.candidates),
            v!("pair_tets", self.pair_tets),
            v!("pair_info", self.pair_info),
            v!("pair_geometry", self.pair_geometry),
            v!("pair_planes", self.pair_planes),
            v!("linearized", self.linearized),
            v!("lin_of", self.lin_of),
            v!("witness", self.witness),
            v!("contrib", self.contrib),
            v!("gather_slot", self.gather_slot),
            v!("thermal_only", self.thermal_only),
            v!("thermal_tets", self.thermal_tets),
            v!("part_tets.tets", self.part_tets.tets),
            v!("part_tets.x", self.part_tets.x),
            v!("x_detect", self.x_detect),
            ("contact_local", self.contact_local.capacity() * 8),
            ("search trees", self.search.held_bytes()),
            ("pair forces", self.pair_forces.held_bytes()),
            (
                "send_slots",
                self.send_slots.iter().map(|s| s.capacity() * 4).sum(),
            ),
        ]
    }

    /// How many of each: elements, candidate pairs, force contributions
    /// (of which received from neighbours), pair tets, local nodes.
    pub fn held_counts(&self) -> Vec<(&'static str, usize)> {
        vec![
            ("elements", self.elements.len()),
            ("candidates", self.candidates.len()),
            ("contributions", self.contrib.len()),
            ("received", self.recv_at.iter().map(|r| r.1).sum()),
            ("pair tets", self.pair_tets.len()),
            ("nodes", self.x.len()),
        ]
    }
}

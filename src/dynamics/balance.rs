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

//! The heat flowing between bodies at an instant (issue 20): through each
//! contact pair (seed 000 eqs 24–30, or a table's or CMY's conductance) and
//! across each near-field gap (conduction, convection and radiation, seed
//! 001 secs 7.1.4–7.1.6), and the contacts' conductance Σ S/Rc at the
//! current temperatures. Pure: the caller gathers the temperatures.

use crate::contact::{local_conductance_block, rank_one_conductance_block, ContactOperator};
use crate::contact::{ContactSet, DeltaT};
use crate::model::Model;

use super::assembly::{gap_law, gap_unit, laws, pair_law, pair_resistance, pair_unit};
use super::exchange::unit_heat;
use super::radiation::{grey_exchange, STEFAN_BOLTZMANN};

/// This rank's share of the flows.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Flows {
    /// Σ S/Rc of the pairs at the current temperatures (W/K).
    pub conductance: f64,
    /// Σ |heat| through the pairs, from one body into the other (W).
    pub contact: f64,
    /// Σ |heat| conducted and convected across the gap links (W).
    pub gap: f64,
    /// Σ |heat| radiated across the gap links (W).
    pub gap_radiation: f64,
}

/// The PETSc rows whose temperatures [`flows`] reads, in its order: each
/// pair's 8, then each gap link's 6.
pub fn flow_rows(contacts: &ContactSet) -> impl Iterator<Item = i32> + '_ {
    let pairs = contacts.dofs.iter().flat_map(|d| d.petsc.map(|r| r as i32));
    let gaps = contacts
        .gaps
        .iter()
        .flat_map(|l| l.rows_a.iter().chain(&l.rows_b).map(|&r| r as i32));
    pairs.chain(gaps)
}

/// The flows of this rank's pairs and gap links at temperatures `t` (the
/// rows of [`flow_rows`]). Pairs of the average-ΔT coupling count S/Rc
/// but not their heat (it is not pairwise).
pub fn flows(model: &Model, contacts: &ContactSet, t: &[f64]) -> Flows {
    let mut out = Flows::default();
    let Some(c) = model.contact.as_ref() else {
        return out;
    };
    let block = match c.operator {
        ContactOperator::RankOne => rank_one_conductance_block,
        ContactOperator::Links => local_conductance_block,
    };
    let laws = laws(model);
    for (k, (p, d)) in contacts.local.iter().zip(&contacts.dofs).enumerate() {
        let tl = &t[8 * k..8 * k + 8];
        let law = pair_law(model, d);
        let q = match law {
            Some(law) => {
                let u = pair_unit(p, d, law, block);
                out.conductance += p.area() * laws.eval(&law, mean(&u.mean, tl)).0;
                unit_heat(&u, &laws, tl).0
            }
            None => {
                let rc = pair_resistance(model, d, 0.0);
                if !rc.is_finite() {
                    continue;
                }
                out.conductance += p.area() / rc;
                let b = block(p, rc);
                let mut q = [0.0; 8];
                for (i, qi) in q.iter_mut().enumerate() {
                    *qi = (0..8).map(|j| b[8 * i + j] * tl[j]).sum();
                }
                q
            }
        };
        if c.delta_t == DeltaT::Local {
            out.contact += q[..4].iter().sum::<f64>().abs();
        }
    }
    let Some(gs) = c.gap.as_ref() else {
        return out;
    };
    let at = 8 * contacts.local.len();
    for (k, l) in contacts.gaps.iter().enumerate() {
        let tl = &t[at + 6 * k..at + 6 * k + 6];
        let u = gap_unit(l, gap_law(model, gs, l));
        let q: f64 = unit_heat(&u, &laws, tl).0[..3].iter().sum();
        out.gap += q.abs();
        if gs.radiation {
            let [ea, eb] = l.materials.map(|m| model.materials[m as usize].emissivity);
            let vf = gs
                .view_factor_table
                .as_ref()
                .map_or(gs.view_factor, |f| f.eval(l.gap).0);
            let g = STEFAN_BOLTZMANN * vf * grey_exchange(ea, eb);
            let off = model.thermal.offset;
            let u4: Vec<f64> = tl.iter().map(|x| (x + off).powi(4)).collect();
            let r: f64 = (0..3)
                .map(|i| g * (0..6).map(|j| u.lap[8 * i + j] * u4[j]).sum::<f64>())
                .sum();
            out.gap_radiation += r.abs();
        }
    }
    out
}

fn mean(m: &[f64; 8], t: &[f64]) -> f64 {
    t.iter().zip(m).map(|(a, b)| a * b).sum()
}

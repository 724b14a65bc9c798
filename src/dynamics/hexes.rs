//! The Hex8 elements of a rank's mechanics (issue 21). Each hex's six
//! tets stay in the element list (marked [`HEX_TET`], which the Tet4
//! kernel skips) so that the contribution slots, the gather in global
//! element order and the halo exchange are the Tet4 ones: the hex kernel
//! (`mechanics::hex8_element`, selective-reduced with hourglass control)
//! writes its eight nodal forces into eight of its tets' 24 corner slots
//! and zeros into the rest, and its mean stress into all six tets' slots
//! (which the output reads). A hex's tets are one block of consecutive
//! elements in either class of `order_elements` (a hex touches the halo
//! when any of its nodes is a ghost), so its slot is its first tet's.

use std::ops::Range;

use nalgebra::{Matrix3, Vector3};

use crate::mechanics::explicit::HEX_TET;
use crate::mechanics::frequency::stable_step;
use crate::mechanics::hex8_element::{hex8_forces_at, Hex8Material, Hex8Reference};
use crate::mechanics::{ElasticMaterial, MechElement, MechanicsError, ThermalState};
use crate::parallel::PartHex;

/// One hex of the domain.
#[derive(Debug, Clone)]
pub(super) struct HexElement {
    /// Global id of its first tet.
    pub(super) gid_first: u32,
    /// Local nodes (seed 002 Table 1 order).
    pub(super) nodes: [u32; 8],
    /// Per node: (tet after the first, corner) whose slot carries it.
    pub(super) corner: [(u8, u8); 8],
    pub(super) reference: Hex8Reference,
    pub(super) material: u32,
    /// Its body.
    pub(super) body: u32,
    /// Element index of its first tet (refreshed by `order_elements`).
    pub(super) slot: u32,
}

/// The hexes of the domain, by ascending `gid_first`.
#[derive(Debug, Clone, Default)]
pub(super) struct DomainHexes {
    pub(super) list: Vec<HexElement>,
}

impl DomainHexes {
    /// The hex of `part_hex` (its first tet has global id `gid_first`),
    /// of material `material` and body `body`.
    pub(super) fn element(
        part_hex: &PartHex,
        gid_first: u32,
        coords: impl Fn(u32) -> [f64; 3],
        (material, body): (u32, u32),
    ) -> Result<HexElement, MechanicsError> {
        let reference = Hex8Reference::from_coords(&part_hex.nodes.map(coords))?;
        Ok(HexElement {
            gid_first,
            nodes: part_hex.nodes,
            corner: part_hex.corner,
            reference,
            material,
            body,
            slot: 0,
        })
    }

    pub(super) fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The hex element global id `gid` belongs to, if any.
    fn of_gid(&self, gid: u32) -> Option<&HexElement> {
        let k = self.list.partition_point(|h| h.gid_first <= gid);
        (k > 0)
            .then(|| &self.list[k - 1])
            .filter(|h| gid - h.gid_first < 6)
    }

    /// Whether element `el` (global id `gid`) touches a ghost node: for a
    /// hex's tet, whether its hex does.
    pub(super) fn touches(&self, el: &MechElement, gid: u32, n_owned: usize) -> bool {
        let ghost = |l: &u32| *l as usize >= n_owned;
        if el.material != HEX_TET {
            return el.nodes.iter().any(ghost);
        }
        let h = self.of_gid(gid).expect("a hex's tet has its hex");
        h.nodes.iter().any(ghost)
    }

    /// Find each hex's first tet among the elements (global ids `ids`).
    pub(super) fn locate(&mut self, ids: &[u32], elements: &[MechElement]) {
        if self.list.is_empty() {
            return;
        }
        for (i, (&gid, el)) in ids.iter().zip(elements).enumerate() {
            if el.material == HEX_TET {
                let k = self.list.partition_point(|h| h.gid_first < gid);
                if let Some(h) = self.list.get_mut(k).filter(|h| h.gid_first == gid) {
                    h.slot = i as u32;
                }
            }
        }
    }

    /// Element ΔT of each hex (the mean of its eight nodes' temperatures
    /// minus the stress-free one, as the Tet4's mean of four) into its
    /// six tets' entries of `delta_t`.
    pub(super) fn element_temperatures(&self, node_t: &[f64], tref: &[f64], delta_t: &mut [f64]) {
        for h in &self.list {
            let s = h.slot as usize;
            let mean = h.nodes.iter().map(|&l| node_t[l as usize]).sum::<f64>() / 8.0;
            delta_t[s..s + 6].fill(mean - tref[s]);
        }
    }

    /// Forces, stresses and stored energy of the hexes whose first tet
    /// lies in `range` of the elements; `delta_t`, `rate`, `out` and
    /// `stress` are those elements' (indexed from `range.start`). Errors
    /// name the element index (from `range.start`) of the hex's first tet.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn forces(
        &self,
        range: Range<usize>,
        materials: &[ElasticMaterial],
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        delta_t: &[f64],
        rate: &[f64],
        out: &mut [[Vector3<f64>; 4]],
        stress: &mut [Matrix3<f64>],
    ) -> Result<f64, MechanicsError> {
        let mut energy = 0.0;
        let kernel: Vec<Hex8Material> = materials.iter().map(Hex8Material::new).collect();
        for h in self
            .list
            .iter()
            .filter(|h| range.contains(&(h.slot as usize)))
        {
            let s = h.slot as usize - range.start;
            let th = ThermalState {
                delta_t: delta_t[s],
                rate: rate[s],
            };
            let r = hex8_forces_at(
                &h.reference,
                &kernel[h.material as usize],
                x,
                v,
                &h.nodes,
                th,
            )
            .map_err(|e| e.at_element(s))?;
            out[s..s + 6].fill([Vector3::zeros(); 4]);
            for (k, &(t, c)) in h.corner.iter().enumerate() {
                out[s + t as usize][c as usize] = r.forces[k];
            }
            stress[s..s + 6].fill(r.mean_stress);
            energy += r.strain_energy;
        }
        Ok(energy)
    }

    /// The stable step of the hexes (`Hex8Reference::critical_dt` with the
    /// viscous reduction of the Tet4 bound, a body's particles adding
    /// their ω² `particle_w2` as to its Tet4 elements; with a contact
    /// penalty `pn`, the element bound with the hex's shortest length), and
    /// that length.
    pub(super) fn time_step(
        &self,
        materials: &[ElasticMaterial],
        pn: Option<f64>,
        particle_w2: &[(u32, f64)],
    ) -> (f64, f64) {
        let (mut dt, mut len) = (f64::INFINITY, f64::INFINITY);
        for h in &self.list {
            let mat = &materials[h.material as usize];
            let w2: f64 = particle_w2
                .iter()
                .filter(|&&(b, _)| b == h.body)
                .map(|&(_, w2)| w2)
                .sum();
            let omega = (4.0 / h.reference.critical_dt(mat).powi(2) + w2).sqrt();
            dt = dt.min(stable_step(
                omega,
                mat.viscosity / mat.p_wave_modulus() * omega,
            ));
            let l = 2.0 * h.reference.min_half_length;
            len = len.min(l);
            if let Some(pn) = pn {
                // Not numbered in the seeds: a penalty p_n acts like a modulus, Δt ≤ L sqrt(ρ/p_n).
                dt = dt.min(l * (mat.density / pn).sqrt());
            }
        }
        (dt, len)
    }
}

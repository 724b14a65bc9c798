//! Thermal shock of a packing (issue 19, beyond the papers): 50 jointed
//! ceramic nuts on a lattice stand on a plate held at 300 °C. Heat enters
//! the bottom layer through the contact faces, and the hot faces expanding
//! against the cold rest of each nut crack it. Asserted: the temperatures
//! stay in [20, 300] °C and the heat balances; the bottom layer cracks
//! before the top one; the per-particle table and its plot agree with the
//! history; the energy per unit of crack area is at least G_I; and 1 and 2
//! ranks break the same joints at the same moments (energies to 1e-8).

use crate::common::*;

/// scenarios/packing-thermal-shock.toml.
const G_I: f64 = 20.0;
const T_COLD: f64 = 20.0;
const T_HOT: f64 = 300.0;
/// Lattice layer height.
const LAYER: f64 = 0.0155;

#[test]
fn a_packing_of_ceramic_nuts_cracks_where_the_plate_heats_it() {
    let scen = root().join("scenarios/packing-thermal-shock.toml");
    let stem = "packing-thermal-shock";
    let mut csv = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("packing-thermal-shock-{ranks}"));
        run_ok(ranks, &scen, &out, &[]);
        csv.push(std::fs::read_to_string(out.join(format!("{stem}_cracks.csv"))).unwrap());
        assert!(out.join(format!("{stem}_particle_cracks.png")).is_file());
        if ranks == 1 {
            continue;
        }
        let nuts = crack_table(&csv[1]);
        assert_eq!(nuts.len(), 50);
        assert_cracked_packing(&out, stem, &nuts, (T_COLD, T_HOT), G_I);
        // The bottom layer, on the hot plate, cracks first.
        let (bottom, top): (Vec<&CrackRow>, Vec<&CrackRow>) =
            nuts.iter().partition(|p| p.z < 0.5 * LAYER);
        assert_eq!((bottom.len(), top.len()), (25, 25));
        let first_top = top
            .iter()
            .filter_map(|p| p.first)
            .fold(f64::INFINITY, f64::min);
        for p in &bottom {
            let t = p
                .first
                .unwrap_or_else(|| panic!("{} on the plate did not crack", p.name));
            assert!(
                t < first_top,
                "{} cracked at {t} s, a top nut at {first_top}",
                p.name
            );
        }
        let times: Vec<f64> = bottom.iter().filter_map(|p| p.first).collect();
        eprintln!(
            "bottom layer cracks from {:.4} s to {:.4} s; top layer: {}",
            times.iter().copied().fold(f64::INFINITY, f64::min),
            times.iter().copied().fold(0.0, f64::max),
            if first_top.is_finite() {
                format!("from {first_top} s")
            } else {
                "no crack".into()
            }
        );
    }
    // The same joints break at the same moments on 1 and 2 ranks (the
    // temperatures agree to the solver's tolerance, so the energies to 1e-8).
    assert_same_cracks(&crack_table(&csv[0]), &crack_table(&csv[1]));
}

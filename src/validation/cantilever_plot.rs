//! Seed 002 Fig 8 as a PNG: the deflection along the cantilever for the
//! FE model, the DE model and the coupled model of
//! [`super::cantilever`] and [`super::coupled_cantilever`], with the
//! Euler–Bernoulli + Timoshenko reference (dashed).

use std::path::Path;

use super::cantilever::{Cantilever, StaticSolution};
use crate::io::plot::{write_png, LinePlot, PlotError, Series};

/// Writes the deflection profiles (mm against x in mm) of `fe`, `de` and
/// `coupled` on `beam`, with the analytic curve, as a PNG at `path`.
pub fn write_fig8(
    beam: &Cantilever,
    fe: &StaticSolution,
    de: &StaticSolution,
    coupled: &StaticSolution,
    path: &Path,
) -> Result<(), PlotError> {
    let mm = |s: &StaticSolution| -> Vec<(f64, f64)> {
        s.profile.iter().map(|(x, u)| (x * 1e3, u * 1e3)).collect()
    };
    let (fe, de, coupled) = (mm(fe), mm(de), mm(coupled));
    let analytic: Vec<(f64, f64)> = (0..=100)
        .map(|i| {
            let x = beam.length * i as f64 / 100.0;
            (x * 1e3, beam.deflection(x) * 1e3)
        })
        .collect();
    let title = format!(
        "Cantilever of seed 002 (Fig 8): L = {} mm, P = {} N",
        beam.length * 1e3,
        beam.load
    );
    let plot = LinePlot {
        title: &title,
        x_label: "x [mm]",
        y_label: "deflection along -z [mm]",
        series: vec![
            Series {
                label: "FE (Hex8, h = 0.5 mm)",
                points: &fe,
                dashed: false,
            },
            Series {
                label: "DE (spheres, r = 0.125 mm)",
                points: &de,
                dashed: false,
            },
            Series {
                label: "coupled FE | DE | FE",
                points: &coupled,
                dashed: false,
            },
            Series {
                label: "Euler-Bernoulli + Timoshenko shear",
                points: &analytic,
                dashed: true,
            },
        ],
    };
    write_png(&plot, path, (1000, 650))
}

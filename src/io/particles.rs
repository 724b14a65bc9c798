//! Temperature statistics over many particles (seed 000 sec 6, Fig 20): the
//! mean, min and max particle temperature against time, and the particle
//! temperature against the distance from the container's axis at a few
//! times, as CSV files and PNG plots. Pure bookkeeping; the caller gathers
//! per-body statistics and calls [`ParticleReport::write`] on one rank.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::plot::{write_png, LinePlot, Series};
use super::IoError;

/// Per-body (min, volume-weighted mean, max) nodal temperature.
pub type BodyStat = [f64; 3];

/// The particles and what has been recorded about them.
#[derive(Debug, Clone)]
pub struct ParticleReport {
    /// Body indices of the particles.
    pub bodies: Vec<usize>,
    /// Volume of each particle.
    pub volumes: Vec<f64>,
    /// Distance of each particle's centroid from the axis.
    pub radii: Vec<f64>,
    /// Rows: time, mean, min nodal, max nodal, min particle mean, max particle mean.
    pub history: Vec<[f64; 6]>,
    /// Radial bins (edges).
    pub edges: Vec<f64>,
    /// Profiles: (time, mean particle temperature per bin; NaN if empty).
    pub profiles: Vec<(f64, Vec<f64>)>,
}

impl ParticleReport {
    /// `radii` from each particle's centroid; `bins` equal radial bins out
    /// to the largest radius.
    pub fn new(bodies: Vec<usize>, volumes: Vec<f64>, radii: Vec<f64>, bins: usize) -> Self {
        let rmax = radii.iter().copied().fold(0.0, f64::max) * (1.0 + 1e-9);
        let edges = (0..=bins).map(|i| rmax * i as f64 / bins as f64).collect();
        ParticleReport {
            bodies,
            volumes,
            radii,
            history: Vec::new(),
            edges,
            profiles: Vec::new(),
        }
    }

    /// Record one time from every body's statistics.
    pub fn record(&mut self, time: f64, stats: &[BodyStat]) {
        let mut vsum = 0.0;
        let mut tsum = 0.0;
        let mut row = [
            time,
            0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for (k, &b) in self.bodies.iter().enumerate() {
            let [lo, mean, hi] = stats[b];
            vsum += self.volumes[k];
            tsum += self.volumes[k] * mean;
            row[2] = row[2].min(lo);
            row[3] = row[3].max(hi);
            row[4] = row[4].min(mean);
            row[5] = row[5].max(mean);
        }
        row[1] = tsum / vsum;
        self.history.push(row);
    }

    /// Record a radial profile: the volume-weighted mean of the particle
    /// temperatures in each bin.
    pub fn record_profile(&mut self, time: f64, stats: &[BodyStat]) {
        let nb = self.edges.len() - 1;
        let mut sum = vec![0.0; nb];
        let mut vol = vec![0.0; nb];
        let rmax = self.edges[nb];
        for (k, &b) in self.bodies.iter().enumerate() {
            let i = ((self.radii[k] / rmax * nb as f64) as usize).min(nb - 1);
            sum[i] += self.volumes[k] * stats[b][1];
            vol[i] += self.volumes[k];
        }
        let prof = sum
            .iter()
            .zip(&vol)
            .map(|(s, v)| if *v > 0.0 { s / v } else { f64::NAN })
            .collect();
        self.profiles.push((time, prof));
    }

    /// Write `<stem>_particles.csv/.png` and `<stem>_radial.csv/.png` into
    /// `dir`; returns the paths written.
    pub fn write(&self, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, IoError> {
        let mut out = Vec::new();
        let csv = dir.join(format!("{stem}_particles.csv"));
        let mut text =
            String::from("time,mean_T,min_T,max_T,min_particle_mean_T,max_particle_mean_T\n");
        for r in &self.history {
            let cells: Vec<String> = r.iter().map(|x| format!("{x:.10e}")).collect();
            text.push_str(&cells.join(","));
            text.push('\n');
        }
        write_atomic(&csv, &text)?;
        out.push(csv);
        let col =
            |i: usize| -> Vec<(f64, f64)> { self.history.iter().map(|r| (r[0], r[i])).collect() };
        let (mean, lo, hi, plo, phi) = (col(1), col(2), col(3), col(4), col(5));
        let png = dir.join(format!("{stem}_particles.png"));
        let plot = LinePlot {
            title: "Particle temperature",
            x_label: "time [s]",
            y_label: "temperature",
            series: vec![
                Series {
                    label: "mean",
                    points: &mean,
                    dashed: false,
                },
                Series {
                    label: "min (nodes)",
                    points: &lo,
                    dashed: true,
                },
                Series {
                    label: "max (nodes)",
                    points: &hi,
                    dashed: true,
                },
                Series {
                    label: "coldest particle (mean)",
                    points: &plo,
                    dashed: false,
                },
                Series {
                    label: "hottest particle (mean)",
                    points: &phi,
                    dashed: false,
                },
            ],
        };
        write_png(&plot, &png, (1000, 700)).map_err(|e| IoError::invalid(&png, e.to_string()))?;
        out.push(png);
        if !self.profiles.is_empty() {
            let nb = self.edges.len() - 1;
            let mids: Vec<f64> = (0..nb)
                .map(|i| 0.5 * (self.edges[i] + self.edges[i + 1]))
                .collect();
            let csv = dir.join(format!("{stem}_radial.csv"));
            let mut text = String::from("radius");
            for (t, _) in &self.profiles {
                text.push_str(&format!(",T_at_{t}s"));
            }
            text.push('\n');
            for (i, r) in mids.iter().enumerate() {
                text.push_str(&format!("{r:.6e}"));
                for (_, p) in &self.profiles {
                    text.push_str(&format!(",{:.10e}", p[i]));
                }
                text.push('\n');
            }
            write_atomic(&csv, &text)?;
            out.push(csv);
            let labels: Vec<String> = self
                .profiles
                .iter()
                .map(|(t, _)| format!("t = {t} s"))
                .collect();
            let points: Vec<Vec<(f64, f64)>> = self
                .profiles
                .iter()
                .map(|(_, p)| mids.iter().copied().zip(p.iter().copied()).collect())
                .collect();
            let png = dir.join(format!("{stem}_radial.png"));
            let plot = LinePlot {
                title: "Particle temperature against distance from the axis",
                x_label: "radius [m]",
                y_label: "temperature",
                series: labels
                    .iter()
                    .zip(&points)
                    .map(|(l, p)| Series {
                        label: l,
                        points: p,
                        dashed: false,
                    })
                    .collect(),
            };
            write_png(&plot, &png, (1000, 700))
                .map_err(|e| IoError::invalid(&png, e.to_string()))?;
            out.push(png);
        }
        Ok(out)
    }
}

fn write_atomic(path: &Path, text: &str) -> Result<(), IoError> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let mut f = std::fs::File::create(&tmp).map_err(|e| IoError::io(&tmp, "creating", e))?;
    f.write_all(text.as_bytes())
        .map_err(|e| IoError::io(&tmp, "writing", e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| IoError::io(path, "renaming", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_and_files() {
        // Bodies 0 (container, not a particle), 1 and 2 (particles).
        let mut r = ParticleReport::new(vec![1, 2], vec![1.0, 3.0], vec![0.1, 0.2], 2);
        r.record(0.0, &[[300.0; 3], [0.0, 1.0, 2.0], [2.0, 5.0, 9.0]]);
        let h = r.history[0];
        assert_eq!(h[1], (1.0 + 15.0) / 4.0);
        assert_eq!((h[2], h[3], h[4], h[5]), (0.0, 9.0, 1.0, 5.0));
        r.record_profile(0.0, &[[300.0; 3], [0.0, 1.0, 2.0], [2.0, 5.0, 9.0]]);
        assert_eq!(r.profiles[0].1, vec![1.0, 5.0]);
        r.record(1.0, &[[300.0; 3], [1.0, 2.0, 3.0], [3.0, 6.0, 9.0]]);
        let dir = tempfile::tempdir().unwrap();
        let files = r.write(dir.path(), "x").unwrap();
        assert_eq!(files.len(), 4);
        let csv = std::fs::read_to_string(dir.path().join("x_particles.csv")).unwrap();
        assert_eq!(csv.lines().count(), 3);
        assert!(
            std::fs::metadata(dir.path().join("x_radial.png"))
                .unwrap()
                .len()
                > 1000
        );
    }
}

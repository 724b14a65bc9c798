//! Helpers for the validation tests: run the `fdem` binary (directly or
//! under `mpirun -n N`) and read its HDF5 output back in original node order.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh output directory under the target dir.
pub fn out_dir(name: &str) -> PathBuf {
    let d = root().join("target").join("test-output").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The Open MPI settings of every fdem process the tests start (its
/// start-up is most of a small case's time, and the tests start about a
/// thousand):
/// - as root, oversubscribed (2 cores, up to 8 ranks);
/// - the `ob1` transport (shared memory on one machine): choosing the
///   default probes UCX first, 0.2 s a process here;
/// - a one-rank run without its own server process (`ess_singleton_isolated`;
///   fdem spawns no processes): 0.1 s less;
/// - `odls_base_sigkill_timeout = 0`: when a rank exits non-zero (every
///   bad-input case on 2 ranks) mpirun otherwise waits about 2 s before it
///   returns, though every rank has already left.
///
/// The benchmarks and `scripts/run.sh` keep Open MPI's defaults.
pub const MPI_ENV: [(&str, &str); 6] = [
    ("OMPI_ALLOW_RUN_AS_ROOT", "1"),
    ("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"),
    ("OMPI_MCA_rmaps_base_oversubscribe", "1"),
    ("OMPI_MCA_pml", "ob1"),
    ("OMPI_MCA_ess_singleton_isolated", "1"),
    ("OMPI_MCA_odls_base_sigkill_timeout", "0"),
];

/// Run `fdem ARGS` on `ranks` ranks (with [`MPI_ENV`]).
pub fn fdem(ranks: usize, args: &[&str]) -> Output {
    let bin = env!("CARGO_BIN_EXE_fdem");
    let mut cmd = if ranks > 1 {
        let mut c = Command::new("mpirun");
        c.args(["-n", &ranks.to_string(), "--oversubscribe", bin]);
        c
    } else {
        Command::new(bin)
    };
    cmd.args(args).envs(MPI_ENV);
    cmd.output().expect("cannot start fdem")
}

/// Run a scenario and panic with its output if it fails. Returns stdout.
pub fn run_ok(ranks: usize, scenario: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "run",
        scenario.to_str().unwrap(),
        "--quiet",
        "--output",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = fdem(ranks, &args);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "fdem {args:?} on {ranks} rank(s) failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

/// Results of a run, indexed by original node id.
pub struct Results {
    /// Output times.
    pub times: Vec<f64>,
    /// Coordinates by original node id.
    pub coords: Vec<[f64; 3]>,
    /// Temperature per output step, by original node id.
    pub temperature: Vec<Vec<f64>>,
}

/// Output times, the mesh as written, the original node id of every row,
/// and the coordinates by original node id.
pub fn read_nodes(h5: &Path) -> (Vec<f64>, fdem::io::MeshData, Vec<i32>, Vec<[f64; 3]>) {
    let times = fdem::io::read_times(h5).unwrap();
    let mesh = fdem::io::read_mesh(h5).unwrap();
    let ids = fdem::io::read_static_node_field_i32(h5, "node_id").unwrap();
    let mut coords = vec![[0.0; 3]; ids.len()];
    for (row, &id) in ids.iter().enumerate() {
        coords[id as usize] = mesh.coords[row];
    }
    (times, mesh, ids, coords)
}

/// Read `<dir>/<stem>.h5` back, reordering rows to original node ids.
pub fn read_results(dir: &Path, stem: &str) -> Results {
    let h5 = dir.join(format!("{stem}.h5"));
    let (times, _, ids, coords) = read_nodes(&h5);
    let n = ids.len();
    let temperature = (0..times.len())
        .map(|k| {
            let t = fdem::io::read_node_field_step(&h5, "temperature", k).unwrap();
            let mut by_id = vec![0.0; n];
            for (row, &id) in ids.iter().enumerate() {
                by_id[id as usize] = t[row];
            }
            by_id
        })
        .collect();
    Results {
        times,
        coords,
        temperature,
    }
}

/// Index of the output step at time `t`.
pub fn step_at(r: &Results, t: f64) -> usize {
    r.times
        .iter()
        .position(|&x| (x - t).abs() < 1e-9 * t.max(1.0))
        .unwrap_or_else(|| panic!("no output at t = {t}; have {:?}", r.times))
}

/// Largest relative difference between two fields, relative to the largest magnitude.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a
        .iter()
        .chain(b)
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(1e-300);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// Parse a "key value" figure from the run summary, e.g. "per step".
pub fn summary_line<'a>(stdout: &'a str, key: &str) -> Option<&'a str> {
    stdout.lines().find(|l| l.trim_start().starts_with(key))
}

/// The number just before `key` in a summary line (`(` stripped), e.g. the
/// 42 of "..., 42 pair evaluations".
pub fn number_before(line: &str, key: &str) -> f64 {
    let at = line
        .find(key)
        .unwrap_or_else(|| panic!("no `{key}` in {line}"));
    let word = line[..at].split_whitespace().last().unwrap();
    word.trim_start_matches('(').parse().unwrap()
}

/// The history CSV of a run: header and rows.
pub fn history(dir: &Path, stem: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(dir.join(format!("{stem}_history.csv"))).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

/// Index of a history column.
pub fn col(h: &[String], name: &str) -> usize {
    h.iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {h:?}"))
}

/// Assert two runs produced the same output times and temperatures at every
/// output step, to `tol` relative (`rel_diff`).
pub fn assert_same_temperatures(r1: &Results, r2: &Results, tol: f64, what: &str) {
    assert_eq!(r1.times, r2.times, "{what}: output times differ");
    for k in 0..r1.times.len() {
        let d = rel_diff(&r1.temperature[k], &r2.temperature[k]);
        assert!(
            d < tol,
            "{what}: step {k} (t = {}): relative difference {d:e}",
            r1.times[k]
        );
    }
}

/// Assert every temperature at every output of `r` lies in `[lo, hi]` (the
/// range of the initial and boundary values: the discrete maximum
/// principle), to round-off of the range. Returns the (min, max) seen.
pub fn assert_within_bounds(r: &Results, lo: f64, hi: f64, what: &str) -> (f64, f64) {
    let tol = 1e-9 * (hi - lo).abs().max(1.0);
    let (mut tmin, mut tmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for (k, t) in r.temperature.iter().enumerate() {
        for (n, &x) in t.iter().enumerate() {
            assert!(
                x >= lo - tol && x <= hi + tol,
                "{what}: node {n} at t = {} has T = {x}, outside [{lo}, {hi}]",
                r.times[k]
            );
            tmin = tmin.min(x);
            tmax = tmax.max(x);
        }
    }
    (tmin, tmax)
}

/// Mechanical output of a run, nodes by original id.
pub struct Mech {
    pub times: Vec<f64>,
    pub coords: Vec<[f64; 3]>,
    /// Cells as original node ids, in file order.
    pub cells: Vec<[usize; 4]>,
    /// Displacement per output step, by node id.
    pub disp: Vec<Vec<[f64; 3]>>,
    /// Cauchy stress (full symmetric 3×3) per output step, in file cell order.
    pub stress: Vec<Vec<[[f64; 3]; 3]>>,
    /// Temperature per output step when the thermal problem ran.
    pub temperature: Vec<Vec<f64>>,
}

pub fn read_mech(dir: &Path, stem: &str) -> Mech {
    let h5 = dir.join(format!("{stem}.h5"));
    let (times, mesh, ids, coords) = read_nodes(&h5);
    let n = ids.len();
    let cells = mesh
        .cells
        .iter()
        .map(|c| c.map(|row| ids[row as usize] as usize))
        .collect();
    let by_id3 = |v: Vec<f64>| {
        let mut out = vec![[0.0; 3]; n];
        for (row, &id) in ids.iter().enumerate() {
            out[id as usize] = [v[3 * row], v[3 * row + 1], v[3 * row + 2]];
        }
        out
    };
    let disp = (0..times.len())
        .map(|k| by_id3(fdem::io::read_node_field_step(&h5, "displacement", k).unwrap()))
        .collect();
    // The file holds XDMF Tensor6 rows: xx, xy, xz, yy, yz, zz.
    let stress = (0..times.len())
        .map(|k| {
            fdem::io::read_cell_field_step(&h5, "stress", k)
                .unwrap()
                .chunks_exact(6)
                .map(|c| [[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]])
                .collect()
        })
        .collect();
    let temperature = (0..times.len())
        .filter_map(|k| {
            let t = fdem::io::read_node_field_step(&h5, "temperature", k).ok()?;
            let mut out = vec![0.0; n];
            for (row, &id) in ids.iter().enumerate() {
                out[id as usize] = t[row];
            }
            Some(out)
        })
        .collect();
    Mech {
        times,
        coords,
        cells,
        disp,
        stress,
        temperature,
    }
}

impl Mech {
    pub fn centroid(&self, c: usize) -> [f64; 3] {
        let c = self.cells[c].map(|n| self.coords[n]);
        [0, 1, 2].map(|d| 0.25 * (c[0][d] + c[1][d] + c[2][d] + c[3][d]))
    }

    /// (r, σ_rr, σ_θθ) of every cell about the z axis through (cx, cy).
    pub fn polar_stress(&self, k: usize, cx: f64, cy: f64) -> Vec<(f64, f64, f64)> {
        (0..self.cells.len())
            .map(|c| {
                let p = self.centroid(c);
                let (x, y) = (p[0] - cx, p[1] - cy);
                let r = x.hypot(y);
                let (nx, ny) = (x / r, y / r);
                let s = self.stress[k][c];
                let (sxx, sxy, syy) = (s[0][0], s[0][1], s[1][1]);
                let srr = sxx * nx * nx + 2.0 * sxy * nx * ny + syy * ny * ny;
                let stt = sxx * ny * ny - 2.0 * sxy * nx * ny + syy * nx * nx;
                (r, srr, stt)
            })
            .collect()
    }
}

/// Mean of (σ_rr, σ_θθ) over the cells whose radius falls in each of `bins`
/// equal bins of [r0, r1], with the bin centres.
pub fn binned(p: &[(f64, f64, f64)], r0: f64, r1: f64, bins: usize) -> Vec<(f64, f64, f64)> {
    let mut acc = vec![(0.0, 0.0, 0.0, 0usize); bins];
    for &(r, a, b) in p {
        if r < r0 || r >= r1 {
            continue;
        }
        let i = (((r - r0) / (r1 - r0)) * bins as f64) as usize;
        let e = &mut acc[i.min(bins - 1)];
        e.0 += r;
        e.1 += a;
        e.2 += b;
        e.3 += 1;
    }
    acc.into_iter()
        .filter(|e| e.3 > 0)
        .map(|e| {
            let n = e.3 as f64;
            (e.0 / n, e.1 / n, e.2 / n)
        })
        .collect()
}

/// A bar of length `len` along `axis` (0 = x, 1 = y, 2 = z), 0.2 m square
/// across, on rollers at its three `min` faces and pulled by a traction `t`
/// on its far end along the axis.
pub fn traction_bar(axis: usize, t: f64, young: f64, len: f64) -> String {
    let mut size = [0.2; 3];
    size[axis] = len;
    let mut value = [0.0; 3];
    value[axis] = t;
    let end = ["xmax", "ymax", "zmax"][axis];
    format!(
        r#"
[time]
dt = 0.02
steps = 5

[[materials]]
name = "m"
density = 1000.0
young = {young}
poisson = 0.25

[[bodies]]
name = "bar"
material = "m"
mesh = {{ kind = "box", size = {size:?}, element_size = 0.1 }}

[mechanics]
damping = 600.0

[[mechanics.bc]]
kind = "fixed"
set = "xmin"
components = ["x"]
[[mechanics.bc]]
kind = "fixed"
set = "ymin"
components = ["y"]
[[mechanics.bc]]
kind = "fixed"
set = "zmin"
components = ["z"]
[[mechanics.bc]]
kind = "traction"
set = "{end}"
value = {value:?}
"#
    )
}

/// The last output of a bar along x of length `len` under the end traction
/// `t`: σ_xx = t and no lateral stress in every element (1 %), the end
/// displacement `tip` (1 %).
pub fn assert_uniaxial_bar(m: &Mech, t: f64, len: f64, tip: f64, what: &str) {
    let k = m.times.len() - 1;
    for s in &m.stress[k] {
        assert!(
            (s[0][0] / t - 1.0).abs() < 0.01
                && s[1][1].abs() < 0.01 * t
                && s[2][2].abs() < 0.01 * t,
            "{what}: stress {s:?}, traction {t}"
        );
    }
    let end = m
        .coords
        .iter()
        .zip(&m.disp[k])
        .filter(|(x, _)| (x[0] - len).abs() < 1e-12)
        .map(|(_, u)| u[0])
        .fold(0.0, f64::max);
    assert!(
        (end / tip - 1.0).abs() < 0.01,
        "{what}: end displacement {end:e}, expected {tip:e}"
    );
}

/// The energy balance of a mechanical run's history (issue 19): at every
/// row, the work of the loads equals kinetic + strain + contact + joint +
/// dissipated (damping, friction) + fracture + crack friction energy,
/// within `rtol` of the largest work. Columns a run without joints lacks
/// count as zero.
pub fn assert_energy_balance(h: &[String], rows: &[Vec<f64>], rtol: f64, what: &str) {
    let get = |r: &Vec<f64>, name: &str| h.iter().position(|c| c == name).map_or(0.0, |i| r[i]);
    let w_max = rows
        .iter()
        .map(|r| get(r, "external_work").abs())
        .fold(0.0, f64::max);
    assert!(w_max > 0.0, "{what}: no work done");
    for r in rows {
        let w = get(r, "external_work");
        let stored: f64 = [
            "kinetic_energy",
            "strain_energy",
            "contact_energy",
            "joint_energy",
            "dissipated_energy",
            "fracture_energy",
            "crack_friction",
        ]
        .iter()
        .map(|c| get(r, c))
        .sum();
        assert!(
            (w - stored).abs() <= rtol * w_max,
            "{what}: at t = {}: work {w:e} against the energies' sum {stored:e}",
            get(r, "time")
        );
    }
}

/// One row of `<stem>_cracks.csv` (per-particle crack statistics).
#[derive(Debug, Clone, PartialEq)]
pub struct CrackRow {
    pub name: String,
    pub joints: f64,
    pub broken: f64,
    pub area: f64,
    pub energy: f64,
    pub first: Option<f64>,
    pub z: f64,
}

/// The rows of a `<stem>_cracks.csv`, its header checked.
pub fn crack_table(text: &str) -> Vec<CrackRow> {
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "body,name,joints,broken,crack_area,fracture_energy,first_break,x,y,z"
    );
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            CrackRow {
                name: c[1].to_string(),
                joints: c[2].parse().unwrap(),
                broken: c[3].parse().unwrap(),
                area: c[4].parse().unwrap(),
                energy: c[5].parse().unwrap(),
                first: (!c[6].is_empty()).then(|| c[6].parse().unwrap()),
                z: c[9].parse().unwrap(),
            }
        })
        .collect()
}

/// The same joints broke at the same moments in two runs (1 and 2 ranks):
/// counts, areas and first-break times equal, energies to 1e-8 (the
/// temperatures agree to the solver's tolerance).
pub fn assert_same_cracks(one: &[CrackRow], two: &[CrackRow]) {
    assert_eq!(one.len(), two.len());
    for (a, b) in one.iter().zip(two) {
        assert_eq!(
            (&a.name, a.broken, a.area, a.first),
            (&b.name, b.broken, b.area, b.first),
            "1 against 2 ranks"
        );
        assert!(
            (a.energy - b.energy).abs() <= 1e-8 * a.energy.abs(),
            "{}: {} J against {} J",
            a.name,
            a.energy,
            b.energy
        );
    }
}

/// A thermally shocked packing of jointed nuts, from its history and its
/// per-particle table `nuts`: every nut temperature in [lo, hi] at every
/// row (bounded conduction), heat stored = heat in to 1e-6, the table's
/// broken joints and crack area those of the history, some joint broken,
/// and at least G_I dissipated per unit of crack area (more in mixed mode
/// and in joints damaged but not broken). Returns (broken, area, energy).
pub fn assert_cracked_packing(
    out: &Path,
    stem: &str,
    nuts: &[CrackRow],
    (lo, hi): (f64, f64),
    g_i: f64,
) -> (f64, f64, f64) {
    let (h, rows) = history(out, stem);
    let c = |n: &str| col(&h, n);
    for r in &rows {
        assert!(
            r[c("nut_min_T")] >= lo - 1e-9 && r[c("nut_max_T")] <= hi + 1e-9,
            "t = {}: nut temperatures {} .. {}",
            r[1],
            r[c("nut_min_T")],
            r[c("nut_max_T")]
        );
    }
    let last = rows.last().unwrap();
    let stored = last[c("stored_heat")] - rows[0][c("stored_heat")];
    let inflow = last[c("boundary_heat_in")];
    assert!(
        inflow > 0.0 && (stored - inflow).abs() < 1e-6 * inflow,
        "heat stored {stored} against heat in {inflow}"
    );
    let broken: f64 = nuts.iter().map(|p| p.broken).sum();
    let area: f64 = nuts.iter().map(|p| p.area).sum();
    assert_eq!(broken, last[c("broken_joints")], "table against history");
    assert!((area - last[c("crack_area")]).abs() < 1e-9 * area.max(1e-12));
    assert!(broken > 0.0, "no nut cracked");
    let energy = last[c("fracture_energy")];
    eprintln!(
        "{broken} broken joints, crack area {area:.4e} m^2, {energy:.4e} J: {:.1} J/m^2",
        energy / area
    );
    assert!(energy >= 0.99 * g_i * area, "{energy} J for {area} m^2");
    (broken, area, energy)
}

/// The velocity of every output step of `h5` (`steps` of them), each row
/// moved to the place its static `node_id` names.
pub fn velocities_by_node_id(h5: &std::path::Path, steps: usize) -> Vec<Vec<f64>> {
    let ids = fdem::io::read_static_node_field_i32(h5, "node_id").unwrap();
    (0..steps)
        .map(|k| {
            let v = fdem::io::read_node_field_step(h5, "velocity", k).unwrap();
            let mut by_id = vec![0.0; v.len()];
            for (row, &id) in ids.iter().enumerate() {
                by_id[3 * id as usize..3 * id as usize + 3]
                    .copy_from_slice(&v[3 * row..3 * row + 3]);
            }
            by_id
        })
        .collect()
}

/// Assert a history `got` equals `want` (a run of the same scenario on
/// another rank count): the same columns and rows, the columns `exact`
/// equal, the others to 1e-9 of their scale (a vector's components share
/// it; a column named `_force_` is at least `force_scale`, as a force
/// that is round-off about zero). Sums over the ranks' partial sums
/// follow the partition in their last bits.
pub fn assert_same_history(
    got: &(Vec<String>, Vec<Vec<f64>>),
    want: &(Vec<String>, Vec<Vec<f64>>),
    exact: &[&str],
    force_scale: f64,
    what: &str,
) {
    let ((hp, rp), (h, rows)) = (got, want);
    assert_eq!(hp, h, "{what}: history columns");
    assert_eq!(rp.len(), rows.len(), "{what}: history rows");
    let group = |name: &str| name.trim_end_matches(['x', 'y', 'z']).to_string();
    for (i, name) in h.iter().enumerate() {
        let scale = (0..h.len())
            .filter(|&c| group(&h[c]) == group(name))
            .flat_map(|c| rows.iter().map(move |row| row[c].abs()))
            .fold(0.0, f64::max)
            .max(if name.contains("_force_") {
                force_scale
            } else {
                0.0
            });
        for (a, b) in rp.iter().zip(rows) {
            if exact.contains(&name.as_str()) {
                assert_eq!(a[i], b[i], "{what}: history {name} at step {}", b[0]);
            } else {
                assert!(
                    (a[i] - b[i]).abs() <= 1e-9 * scale,
                    "{what}: history {name} at step {}: {} against {}",
                    b[0],
                    a[i],
                    b[i]
                );
            }
        }
    }
}

/// Temperatures by position (the copies of a vertex sit where it does):
/// per output, each node's temperature with its coordinates' bits.
pub fn by_position(r: &Results) -> Vec<std::collections::HashMap<[u64; 3], f64>> {
    r.temperature
        .iter()
        .map(|t| {
            r.coords
                .iter()
                .zip(t)
                .map(|(c, &v)| (c.map(f64::to_bits), v))
                .collect()
        })
        .collect()
}

/// The global numbers of the joints broken (modes 1–3) in a joint grid's
/// `mode` field.
pub fn broken(mode: &[f64]) -> Vec<usize> {
    (0..mode.len())
        .filter(|&j| (1.0..=3.0).contains(&mode[j]))
        .collect()
}

/// Every copy of a vertex in the jointed run `jointed` has, at each
/// output, the temperature of that vertex in the continuum run `cont`
/// (to 1e-6 absolute: 1e-8 of a 100-degree range).
pub fn assert_copies_at_continuum(jointed: &Results, cont: &Results) {
    assert_eq!(cont.times, jointed.times);
    let at = by_position(cont);
    for (k, t) in jointed.temperature.iter().enumerate() {
        for (c, &v) in jointed.coords.iter().zip(t) {
            let want = at[k][&c.map(f64::to_bits)];
            assert!(
                (v - want).abs() <= 1e-8 * 100.0,
                "output {k}: a copy at {c:?} has {v}, the continuum {want}"
            );
        }
    }
}

/// A cracking run of `scen` (output stem `stem`) on `ranks` ranks into
/// `out`, to 7.6 ms at rtol 1e-12 unless `extra` says otherwise: its
/// temperatures and the modes of its joints at the last output.
pub fn cracking_run(
    ranks: usize,
    scen: &Path,
    out: &Path,
    stem: &str,
    extra: &[&str],
) -> (Results, Vec<f64>) {
    let base = [
        "--set",
        "solver.rtol=1e-12",
        "--set",
        "time.end_time=7.6e-3",
    ];
    run_ok(ranks, scen, out, &[&base[..], extra].concat());
    (read_results(out, stem), last_modes(out, stem))
}

/// The modes of the joints of the run in `out` at its last output.
pub fn last_modes(out: &Path, stem: &str) -> Vec<f64> {
    let jh5 = out.join(format!("{stem}_joints.h5"));
    let k = fdem::io::read_times(&jh5).unwrap().len() - 1;
    fdem::io::read_cell_field_step(&jh5, "mode", k).unwrap()
}

/// What the reference runs of [`cracks_and_restarts_as_on_one_rank`] add
/// to [`cracking_run`]: a checkpoint, to 8 ms.
const CK_ARGS: [&str; 4] = [
    "--set",
    "output.checkpoint=true",
    "--set",
    "time.end_time=8e-3",
];

/// The one-rank run of scenarios/hollow-cylinder-cracking.toml to 8 ms,
/// checkpointing, at rtol 1e-12 (its outputs every 0.2 ms): the reference
/// of tests/joint_split_thermal.rs and tests/thermal_cracking.rs, run once
/// per test process by whichever test asks first (the others wait).
pub fn cracking_cylinder_reference() -> &'static Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let out = out_dir("cracking-cylinder-reference");
        let scen = root().join("scenarios/hollow-cylinder-cracking.toml");
        cracking_run(1, &scen, &out, "hollow-cylinder-cracking", &CK_ARGS);
        out
    })
}

/// The distinct ranks, ascending, holding the elements of the output
/// `<stem>.h5` in `dir` (its `rank` field).
pub fn ranks_held(dir: &Path, stem: &str) -> Vec<i32> {
    let h5 = dir.join(format!("{stem}.h5"));
    let mut r = fdem::io::read_static_cell_field_i32(&h5, "rank").unwrap();
    r.sort_unstable();
    r.dedup();
    r
}

/// A cracking run (`run(ranks, out, extra)`, see [`cracking_run`]; output
/// stem `stem`, directories `<tag>-*`) split on two ranks cracks as on one,
/// and continues from its checkpoint on other rank counts. The one-rank
/// run to 8 ms is the reference (in `reference` if given, made by `run`
/// with [`CK_ARGS`]); the two-rank run to 7.4 ms (after its
/// first joints broke) has at every output the one-rank temperatures (1e-8)
/// and at its last the same broken joints; its checkpoint continues to
/// 8 ms on 3 ranks (a new cut) and on 1 to the reference's broken joints
/// and end temperatures. One test for both: the uninterrupted runs are
/// the costly part, run once. Returns the two-rank run's directory.
pub fn cracks_and_restarts_as_on_one_rank(
    tag: &str,
    stem: &str,
    run: impl Fn(usize, &Path, &[&str]) -> (Results, Vec<f64>),
    reference: Option<&Path>,
) -> PathBuf {
    let ck_args = CK_ARGS;
    let (full, (want, want_mode)) = match reference {
        Some(dir) => (
            dir.to_path_buf(),
            (read_results(dir, stem), last_modes(dir, stem)),
        ),
        None => {
            let full = out_dir(&format!("{tag}-full"));
            let r = run(1, &full, &ck_args);
            (full, r)
        }
    };
    let first = out_dir(&format!("{tag}-first"));
    let stop = [&ck_args[..], &["--set", "time.end_time=7.4e-3"]].concat();
    let (two, first_mode) = run(2, &first, &stop);
    assert_eq!(
        ranks_held(&first, stem),
        vec![0, 1],
        "{tag}: not split over 2 ranks"
    );
    let k = two.times.len() - 1;
    assert_eq!(
        two.times[..],
        want.times[..=k],
        "{tag}: 2 ranks' output times"
    );
    for (i, t) in two.temperature.iter().enumerate() {
        let d = rel_diff(t, &want.temperature[i]);
        let at = two.times[i];
        assert!(
            d < 1e-8,
            "{tag}, 2 ranks, t = {at}: temperatures differ by {d:e}"
        );
    }
    let jh5 = full.join(format!("{stem}_joints.h5"));
    assert_eq!(fdem::io::read_times(&jh5).unwrap()[k], two.times[k]);
    let at_stop = broken(&fdem::io::read_cell_field_step(&jh5, "mode", k).unwrap());
    assert!(!at_stop.is_empty(), "{tag}: no joint broke before 7.4 ms");
    assert_eq!(
        broken(&first_mode),
        at_stop,
        "{tag}: 2 ranks' broken joints differ"
    );
    let ck = first.join(format!("{stem}_checkpoint.h5"));
    for ranks in [3, 1] {
        let rest = out_dir(&format!("{tag}-restart-{ranks}"));
        let more = [&ck_args[..], &["--restart", ck.to_str().unwrap()]].concat();
        let (got, mode) = run(ranks, &rest, &more);
        assert_eq!(
            ranks_held(&rest, stem),
            (0..ranks as i32).collect::<Vec<_>>(),
            "{tag}, restart on {ranks} ranks: not split over all ranks"
        );
        assert_eq!(
            broken(&mode),
            broken(&want_mode),
            "{tag}, restart on {ranks} ranks: broken joints differ"
        );
        let (k, kw) = (got.times.len() - 1, want.times.len() - 1);
        assert_eq!(
            got.times[k], want.times[kw],
            "{tag}, {ranks} ranks: end time"
        );
        let d = rel_diff(&got.temperature[k], &want.temperature[kw]);
        assert!(
            d < 1e-8,
            "{tag}, {ranks} ranks: end temperatures differ by {d:e}"
        );
        eprintln!(
            "{tag}: restart on {ranks} ranks: {} joints broken ({} at 7.4 ms), \
             end temperatures within {d:e}",
            broken(&mode).len(),
            at_stop.len()
        );
    }
    first
}

/// Every output of the particle series `<stem>_particles.h5` in `dir`: its
/// times and, per field (displacement, velocity, temperature where
/// written), per output the values by global particle number (the rows
/// are checked to be in that order).
pub fn particle_fields(dir: &Path, stem: &str) -> (Vec<f64>, Vec<Vec<Vec<f64>>>) {
    let h5 = dir.join(format!("{stem}_particles.h5"));
    let times = fdem::io::read_times(&h5).unwrap();
    let ids = fdem::io::read_static_node_field_i32(&h5, "particle_id").unwrap();
    assert!(ids.iter().enumerate().all(|(r, &i)| i as usize == r));
    let fields = ["displacement", "velocity", "temperature"]
        .iter()
        .filter_map(|name| {
            (0..times.len())
                .map(|k| fdem::io::read_node_field_step(&h5, name, k).ok())
                .collect()
        })
        .collect();
    (times, fields)
}

/// The numbers before "repartition(s)" and "bodies moved" on a run
/// summary's `balance` line.
pub fn repartitions(summary: &str) -> (u64, u64) {
    let line = summary
        .lines()
        .find(|l| l.trim_start().starts_with("balance"))
        .unwrap_or_else(|| panic!("no balance line in\n{summary}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let before = |w: &str| -> u64 {
        let i = words.iter().position(|x| x.starts_with(w)).unwrap();
        words[i - 1].parse().unwrap()
    };
    (before("repartition"), before("bodies"))
}

/// The joint grid's fields damage, mode, broke_at and opening of every
/// output of `<stem>_joints.h5` in `dir` (each by global joint number).
pub fn joint_fields(dir: &Path, stem: &str) -> Vec<[Vec<f64>; 4]> {
    let h5 = dir.join(format!("{stem}_joints.h5"));
    let steps = fdem::io::read_times(&h5).unwrap().len();
    (0..steps)
        .map(|k| {
            ["damage", "mode", "broke_at", "opening"]
                .map(|f| fdem::io::read_cell_field_step(&h5, f, k).unwrap())
        })
        .collect()
}

/// Seed 000 sec 4.2: the mean over nodes of |T − T_analytic| / (T_D − T_i)
/// at output `k`, in percent, against the slab series of
/// `fdem::validation::SlabProblem::seed_000`.
pub fn slab_mean_error_percent(r: &Results, k: usize) -> f64 {
    let p = fdem::validation::SlabProblem::seed_000();
    let t = r.times[k];
    let sum: f64 = r
        .coords
        .iter()
        .zip(&r.temperature[k])
        .map(|(x, &v)| (v - p.temperature(x[0], t)).abs())
        .sum();
    100.0 * sum / r.coords.len() as f64 / (p.t_dirichlet - p.t_initial).abs()
}

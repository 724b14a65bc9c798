//! Tabular contact conductance (issue 20; seed 001 sec 7.1.4, "TCC ... a
//! function of temperature, pressure, geometric penetration ... by tabular
//! input"): h(T, P, g) piecewise linear on a grid, with g > 0 the
//! penetration of a closed contact and g < 0 an open gap, and a
//! temperature table for the gap medium's k(T). Pure: no MPI or PETSc.

use serde::{Deserialize, Serialize};

/// h(T, P, g) on a grid (W/m²/K). Each axis is optional (absent: h does
/// not depend on it); values are listed with the gap varying fastest, then
/// the pressure, then the temperature. Outside an axis's range the end
/// value holds (no extrapolation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConductanceTable {
    /// Temperatures (the scenario's unit, ascending).
    #[serde(default)]
    pub temperature: Vec<f64>,
    /// Contact pressures (Pa, ascending).
    #[serde(default)]
    pub pressure: Vec<f64>,
    /// Gaps (m, ascending): positive a penetration, negative an open gap.
    #[serde(default)]
    pub gap: Vec<f64>,
    /// h at the grid points (W/m²/K), gap fastest.
    pub h: Vec<f64>,
    /// Contact pressure (Pa) of runs without mechanics, where the table
    /// has a pressure axis.
    #[serde(default)]
    pub prescribed_pressure: Option<f64>,
}

/// k(T) of a gap's medium, piecewise linear (W/m/K).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Table1 {
    /// The argument's points, ascending.
    #[serde(alias = "temperature", alias = "gap")]
    pub x: Vec<f64>,
    /// The values there.
    #[serde(alias = "k", alias = "value")]
    pub y: Vec<f64>,
}

/// Where `x` lies on `axis` (ascending): the lower index, the weight of the
/// upper point, and d(weight)/dx (0 outside the range or on a 1-point axis).
fn locate(axis: &[f64], x: f64) -> (usize, f64, f64) {
    let n = axis.len();
    if n < 2 || x <= axis[0] {
        return (0, 0.0, 0.0);
    }
    if x >= axis[n - 1] {
        return (n - 2, 1.0, 0.0);
    }
    let i = axis.partition_point(|&a| a <= x) - 1;
    let w = axis[i + 1] - axis[i];
    (i, (x - axis[i]) / w, 1.0 / w)
}

fn check_axis(key: &str, name: &str, axis: &[f64]) -> Result<(), String> {
    if axis.iter().any(|v| !v.is_finite()) {
        return Err(format!("{key}.{name}: values must be finite"));
    }
    if axis.windows(2).any(|w| w[1] <= w[0]) {
        return Err(format!("{key}.{name}: must be strictly ascending"));
    }
    Ok(())
}

impl ConductanceTable {
    fn dims(&self) -> [usize; 3] {
        [&self.temperature, &self.pressure, &self.gap].map(|a| a.len().max(1))
    }

    /// Whether h depends on the temperature (the step is then nonlinear).
    pub fn depends_on_temperature(&self) -> bool {
        self.temperature.len() > 1
    }

    /// Whether h depends on the pressure.
    pub fn depends_on_pressure(&self) -> bool {
        self.pressure.len() > 1
    }

    /// Whether h depends on the gap.
    pub fn depends_on_gap(&self) -> bool {
        self.gap.len() > 1
    }

    /// The table's errors, naming the key under `key`.
    pub fn check(&self, key: &str) -> Result<(), String> {
        check_axis(key, "temperature", &self.temperature)?;
        check_axis(key, "pressure", &self.pressure)?;
        check_axis(key, "gap", &self.gap)?;
        let [a, b, c] = self.dims();
        if self.h.len() != a * b * c {
            return Err(format!(
                "{key}.h: {} values for a {a} × {b} × {c} grid (temperature × pressure × gap); \
                 need {}",
                self.h.len(),
                a * b * c
            ));
        }
        if let Some(v) = self.h.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!("{key}.h: must be non-negative (W/m²/K), got {v}"));
        }
        match self.prescribed_pressure {
            Some(p) if !(p.is_finite() && p >= 0.0) => Err(format!(
                "{key}.prescribed_pressure: must be non-negative (Pa), got {p}"
            )),
            _ => Ok(()),
        }
    }

    /// Seed 001 sec 7.1.4: h at temperature `t`, pressure `p` and gap `g`
    /// (trilinear on the grid), and ∂h/∂t.
    pub fn eval(&self, t: f64, p: f64, g: f64) -> (f64, f64) {
        let [_, np, ng] = self.dims();
        let (it, wt, dt) = locate(&self.temperature, t);
        let (ip, wp, _) = locate(&self.pressure, p);
        let (ig, wg, _) = locate(&self.gap, g);
        let at = |i: usize, j: usize, k: usize| self.h[(i * np + j) * ng + k];
        // Bilinear in (p, g) at temperature row i.
        let plane = |i: usize| {
            let j1 = if np > 1 { ip + 1 } else { ip };
            let k1 = if ng > 1 { ig + 1 } else { ig };
            let lo = at(i, ip, ig) * (1.0 - wg) + at(i, ip, k1) * wg;
            let hi = at(i, j1, ig) * (1.0 - wg) + at(i, j1, k1) * wg;
            lo * (1.0 - wp) + hi * wp
        };
        if self.temperature.len() < 2 {
            return (plane(0), 0.0);
        }
        let (a, b) = (plane(it), plane(it + 1));
        (a * (1.0 - wt) + b * wt, (b - a) * dt)
    }
}

impl Table1 {
    /// The table's errors, naming the key under `key`.
    pub fn check(&self, key: &str) -> Result<(), String> {
        check_axis(key, "points", &self.x)?;
        if self.x.is_empty() || self.x.len() != self.y.len() {
            return Err(format!(
                "{key}: needs as many values as points, at least one ({} and {})",
                self.x.len(),
                self.y.len()
            ));
        }
        if let Some(v) = self.y.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!("{key}: values must be non-negative, got {v}"));
        }
        Ok(())
    }

    /// The value at `x` (ends held) and its slope.
    pub fn eval(&self, x: f64) -> (f64, f64) {
        if self.x.len() < 2 {
            return (self.y[0], 0.0);
        }
        let (i, w, d) = locate(&self.x, x);
        let (a, b) = (self.y[i], self.y[i + 1]);
        (a + (b - a) * w, (b - a) * d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> ConductanceTable {
        // h = 100 + T + 1e-4 P + 1e5 g on T ∈ {0, 100}, P ∈ {0, 1e6}, g ∈ {-1e-3, 0, 1e-3}.
        let (ts, ps, gs) = (vec![0.0, 100.0], vec![0.0, 1e6], vec![-1e-3, 0.0, 1e-3]);
        let mut h = Vec::new();
        for &t in &ts {
            for &p in &ps {
                for &g in &gs {
                    h.push(100.0 + t + 1e-4 * p + 1e5 * g);
                }
            }
        }
        ConductanceTable {
            temperature: ts,
            pressure: ps,
            gap: gs,
            h,
            prescribed_pressure: None,
        }
    }

    #[test]
    fn a_linear_function_is_reproduced_inside_and_held_outside() {
        let t = table();
        t.check("c").unwrap();
        let (h, dh) = t.eval(30.0, 2.5e5, -4e-4);
        assert!((h - (100.0 + 30.0 + 25.0 - 40.0)).abs() < 1e-9, "{h}");
        assert!((dh - 1.0).abs() < 1e-12);
        // Beyond the ends: the end values, no slope in T.
        let (h, dh) = t.eval(500.0, 5e6, 1.0);
        assert!((h - (100.0 + 100.0 + 100.0 + 100.0)).abs() < 1e-9, "{h}");
        assert_eq!(dh, 0.0);
    }

    #[test]
    fn missing_axes_and_bad_tables() {
        let t = ConductanceTable {
            temperature: vec![],
            pressure: vec![1.0, 2.0],
            gap: vec![],
            h: vec![10.0, 30.0],
            prescribed_pressure: Some(1.5),
        };
        t.check("c").unwrap();
        assert_eq!(t.eval(1e9, 1.5, 7.0), (20.0, 0.0));
        let mut bad = t.clone();
        bad.h.push(1.0);
        assert!(bad.check("c").unwrap_err().contains("c.h: 3 values"));
        let mut bad = t.clone();
        bad.pressure = vec![2.0, 1.0];
        assert!(bad.check("c").unwrap_err().contains("ascending"));
        let mut bad = t;
        bad.h[0] = -1.0;
        assert!(bad.check("c").unwrap_err().contains("non-negative"));
    }

    #[test]
    fn one_dimensional_table() {
        let k = Table1 {
            x: vec![0.0, 100.0, 200.0],
            y: vec![0.02, 0.03, 0.05],
        };
        k.check("k").unwrap();
        let (v, d) = k.eval(150.0);
        assert!((v - 0.04).abs() < 1e-15 && (d - 2e-4).abs() < 1e-15);
        assert_eq!(k.eval(-5.0), (0.02, 0.0));
        assert_eq!(k.eval(500.0), (0.05, 0.0));
    }
}

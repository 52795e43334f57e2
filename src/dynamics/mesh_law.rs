//! The load-dependent mesh law F(δ, ξ): mesh force along the line of action as a function of
//! the mesh deflection δ and the roll position ξ, from a table of static deflections.
//!
//! Row i of the table holds, at roll ξᵢ = i·p_b/N, the static deflection δ_k(ξᵢ) under the total
//! mesh force F_k (k = 0…K, F₀ = 0); δ₀(ξ) is the no-load transmission error, where the flanks
//! first touch: zero for unmodified flanks, a relief's opening where they are modified. Below
//! it the flanks are apart. Between rows the deflections are interpolated
//! linearly in ξ; along a row F(δ) is piecewise linear. Today the rows come from the analytic
//! model (`mesh_stiffness::static_deflection_table`); the static FE analyses of the PMOR-Hertz
//! model give the same kind of table (STE at torque levels).
//!
//! Energy. The potential of the mesh is V(δ, ξ) = ∫₀^δ F dδ′. Through the complementary energy
//! W*(F, ξ) = ∫₀^F δ dF′ it is V = F·δ − W*(F, ξ), and — W* being linear in the row's
//! deflections — ∂V/∂ξ at fixed δ equals −∂W*/∂ξ at fixed F (envelope theorem). Both are exact
//! for the interpolated table, so the force on the roll coordinate, ∂W*/∂ξ, keeps the model
//! conservative. For a linear law δ = F/K(ξ) it is −½K′(ξ)δ².
//!
//! Tooth friction's elastic share (FE-fed laws, issue 42). Friction loads the teeth along the
//! flanks, and that load moves them along the line of action too: at a mesh force F the
//! deflection is δ_k(ξ) + λ·e_k(ξ), with e = ∂δ/∂μ at fixed F from the statics with friction
//! (`rom::static_mesh_law`) and λ = μ × the sense the pair turns in (+1 forward, as the statics;
//! −1 reversed; 0 at rest, where the regularized friction vanishes). For a λ held fixed the law
//! is a table like any other and keeps its potential, with W* + λ·∫e dF; where λ changes (a new
//! μ, a reversal) the potential changes at fixed δ by −λ's change × ∫e dF, which the lumped
//! model books (`LumpedState::friction_elastic_work_j`).

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshLaw {
    pub base_pitch_m: f64,
    /// F₀ = 0 < F₁ < … < F_K (N).
    pub force_levels_n: Vec<f64>,
    /// δ_k(ξᵢ), row-major: N rows of K+1 (m).
    pub deflection_m: Vec<f64>,
    /// W*_k(ξᵢ) = ∫₀^{F_k} δ dF at each row and level, cumulative (J).
    pub complementary_energy_j: Vec<f64>,
    /// Tooth friction's elastic share e_k(ξᵢ) = ∂δ_k(ξᵢ)/∂λ (m per unit λ), laid out as the
    /// deflections; empty where the law has none (the analytic law, a frictionless build).
    pub friction_deflection_m: Vec<f64>,
    /// ∫₀^{F_k} e dF, cumulative as `complementary_energy_j` (J per unit λ); empty with
    /// `friction_deflection_m`.
    pub friction_energy_j: Vec<f64>,
}

/// The cumulative trapezoid ∫₀^{F_k} row dF of each row (J): a law's complementary energy.
fn cumulative_energy(force_levels_n: &[f64], rows: &[f64]) -> Vec<f64> {
    let levels = force_levels_n.len();
    let mut energy = vec![0.0; rows.len()];
    for (row, w) in rows.chunks(levels).zip(energy.chunks_mut(levels)) {
        for k in 1..levels {
            w[k] = w[k - 1] + 0.5 * (row[k - 1] + row[k]) * (force_levels_n[k] - force_levels_n[k - 1]);
        }
    }
    energy
}

/// The law evaluated at one (δ, ξ).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshForce {
    /// Elastic mesh force F (N).
    pub force_n: f64,
    /// Tangent stiffness ∂F/∂δ (N/m).
    pub stiffness_n_per_m: f64,
    /// Elastic energy V (J).
    pub potential_j: f64,
    /// Generalized force on the roll coordinate, −∂V/∂ξ (N).
    pub roll_force_n: f64,
}

impl MeshLaw {
    /// Builds the law from force levels and rows of static deflections (N × (K+1)).
    pub fn new(base_pitch_m: f64, force_levels_n: Vec<f64>, deflection_m: Vec<f64>) -> Self {
        let levels = force_levels_n.len();
        assert!(levels >= 2 && force_levels_n[0] == 0.0 && deflection_m.len() % levels == 0);
        let energy = cumulative_energy(&force_levels_n, &deflection_m);
        MeshLaw {
            base_pitch_m,
            force_levels_n,
            deflection_m,
            complementary_energy_j: energy,
            friction_deflection_m: Vec::new(),
            friction_energy_j: Vec::new(),
        }
    }

    /// The law with tooth friction's elastic share e_k(ξᵢ) (m per unit λ, laid out as the
    /// deflections). `Err` where it has the wrong length, or where λ of `max_lambda` in either
    /// sense would make a row's deflection stop growing with the force (the law would not be
    /// single-valued).
    pub fn with_friction_share(mut self, per_lambda_m: Vec<f64>, max_lambda: f64) -> Result<Self, String> {
        if per_lambda_m.len() != self.deflection_m.len() || per_lambda_m.iter().any(|e| !e.is_finite()) {
            return Err(format!(
                "friction's elastic share: {} finite values needed, one per deflection, got {}",
                self.deflection_m.len(),
                per_lambda_m.len()
            ));
        }
        let k = self.force_levels_n.len();
        for (i, (row, e)) in self.deflection_m.chunks(k).zip(per_lambda_m.chunks(k)).enumerate() {
            for lambda in [-max_lambda, max_lambda] {
                if let Some(m) = (1..k).find(|&m| !(row[m] + lambda * e[m] > row[m - 1] + lambda * e[m - 1])) {
                    return Err(format!(
                        "friction's elastic share at λ = {lambda} makes row {i}'s deflection stop growing from level {} to {m}",
                        m - 1
                    ));
                }
            }
        }
        self.friction_energy_j = cumulative_energy(&self.force_levels_n, &per_lambda_m);
        self.friction_deflection_m = per_lambda_m;
        Ok(self)
    }

    /// Whether the law carries friction's elastic share.
    pub fn has_friction_share(&self) -> bool {
        !self.friction_deflection_m.is_empty()
    }

    /// Checks a law read from outside (a model file): the shape `new` asserts, and finite
    /// numbers (found by fuzzing the model-file decoder: a checksummed file with an empty force
    /// table divided by zero in `rows`).
    pub fn check(&self, name: &str) -> Result<(), String> {
        let levels = self.force_levels_n.len();
        let n = self.deflection_m.len();
        let shape_ok = levels >= 2
            && self.force_levels_n[0] == 0.0
            && self.force_levels_n.windows(2).all(|w| w[1] > w[0] && w[1].is_finite())
            && n >= levels
            && n % levels == 0
            && self.complementary_energy_j.len() == n
            && self.friction_deflection_m.len() == self.friction_energy_j.len()
            && (self.friction_deflection_m.is_empty() || self.friction_deflection_m.len() == n);
        if !shape_ok {
            return Err(format!(
                "the {name} mesh law is malformed: {levels} force levels (need ≥ 2, from 0, increasing), {n} deflections, {} energies",
                self.complementary_energy_j.len()
            ));
        }
        let finite = self
            .deflection_m
            .iter()
            .chain(&self.complementary_energy_j)
            .chain(&self.friction_deflection_m)
            .chain(&self.friction_energy_j)
            .all(|x| x.is_finite());
        if !(finite && self.base_pitch_m.is_normal() && self.base_pitch_m > 0.0) {
            return Err(format!("the {name} mesh law holds a non-finite value or a non-positive base pitch"));
        }
        Ok(())
    }

    pub fn rows(&self) -> usize {
        self.deflection_m.len() / self.force_levels_n.len()
    }

    /// Row i of the deflections and of the complementary energies at friction share λ.
    fn row(&self, i: usize, lambda: f64) -> Row<'_> {
        let k = self.force_levels_n.len();
        let span = i * k..(i + 1) * k;
        let friction = (lambda != 0.0 && self.has_friction_share())
            .then(|| (&self.friction_deflection_m[span.clone()], &self.friction_energy_j[span.clone()], lambda));
        Row { deflection: &self.deflection_m[span.clone()], energy: &self.complementary_energy_j[span], friction }
    }

    /// Evaluates the law; zero for δ ≤ δ₀(ξ) (the flanks do not touch). Beyond the last level
    /// the last segment is extended.
    pub fn evaluate(&self, delta_m: f64, roll_m: f64) -> MeshForce {
        self.evaluate_with_friction(delta_m, roll_m, 0.0)
    }

    /// The law at friction share λ (μ × the sense of rolling, see the module comment).
    pub fn evaluate_with_friction(&self, delta_m: f64, roll_m: f64, lambda: f64) -> MeshForce {
        let dx = self.base_pitch_m / self.rows() as f64;
        let (i, j, t) = self.row_position(roll_m);
        let (a, b) = (self.row(i, lambda), self.row(j, lambda));
        let at = |k: usize| (1.0 - t) * a.deflection(k) + t * b.deflection(k);
        if delta_m <= at(0) {
            return MeshForce::default();
        }
        // Segment m with δ_m(ξ) ≤ δ < δ_{m+1}(ξ): rows increase with k, so bisect.
        let last = self.force_levels_n.len() - 1;
        let (mut lo, mut hi) = (0, last);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if at(mid) <= delta_m {
                lo = mid
            } else {
                hi = mid
            }
        }
        let m = lo.min(last - 1);
        let f = &self.force_levels_n;
        let (d0, d1) = (at(m), at(m + 1));
        let s = (delta_m - d0) / (d1 - d0);
        let force = f[m] + s * (f[m + 1] - f[m]);
        // W* of a row at this force: the cumulative part plus the trapezoid of the segment.
        let w_row = |row: &Row| {
            let d_at_force = row.deflection(m) + s * (row.deflection(m + 1) - row.deflection(m));
            row.energy(m) + 0.5 * (row.deflection(m) + d_at_force) * (force - f[m])
        };
        let (wa, wb) = (w_row(&a), w_row(&b));
        let w_star = (1.0 - t) * wa + t * wb;
        MeshForce {
            force_n: force,
            stiffness_n_per_m: (f[m + 1] - f[m]) / (d1 - d0),
            potential_j: force * delta_m - w_star,
            roll_force_n: (wb - wa) / dx,
        }
    }

    /// Static deflection at force F and roll ξ (the static transmission error under F).
    pub fn static_deflection(&self, force_n: f64, roll_m: f64) -> f64 {
        self.static_deflection_with_friction(force_n, roll_m, 0.0)
    }

    /// Static deflection at force F, roll ξ and friction share λ.
    pub fn static_deflection_with_friction(&self, force_n: f64, roll_m: f64, lambda: f64) -> f64 {
        let (i, j, t) = self.row_position(roll_m);
        let (m, s) = self.level_position(force_n);
        let d = |row: Row| row.deflection(m) + s * (row.deflection(m + 1) - row.deflection(m));
        (1.0 - t) * d(self.row(i, lambda)) + t * d(self.row(j, lambda))
    }

    /// Where roll ξ falls between the rows: (i, i + 1 modulo N, t) with ξ = (i + t)·p_b/N modulo
    /// p_b, t in [0, 1).
    pub fn row_position(&self, roll_m: f64) -> (usize, usize, f64) {
        let n = self.rows();
        let pos = roll_m.rem_euclid(self.base_pitch_m) / (self.base_pitch_m / n as f64);
        let i = (pos.floor() as usize).min(n - 1);
        (i, (i + 1) % n, pos - i as f64)
    }

    /// Where force F falls between the levels: (m, s) with F = F_m + s·(F_{m+1} − F_m); s leaves
    /// [0, 1] beyond the first and last segments.
    pub fn level_position(&self, force_n: f64) -> (usize, f64) {
        let f = &self.force_levels_n;
        let m = f.partition_point(|&x| x <= force_n).clamp(1, f.len() - 1) - 1;
        (m, (force_n - f[m]) / (f[m + 1] - f[m]))
    }

    /// Secant stiffness F / mean-over-ξ static deflection (N/m): what ISO 6336-1's c_γα measures.
    pub fn mean_secant_stiffness(&self, force_n: f64) -> f64 {
        let n = self.rows();
        let dx = self.base_pitch_m / n as f64;
        let mean = (0..n).map(|i| self.static_deflection(force_n, i as f64 * dx)).sum::<f64>() / n as f64;
        force_n / mean
    }

    /// The largest tangent stiffness ∂F/∂δ anywhere in the table (N/m): the stiffest the mesh
    /// gets (beyond the table's top force the law continues with its last slope), at any friction
    /// share λ within ±`max_lambda` (the share is linear in λ, so its ends and 0 bound it).
    pub fn max_tangent_stiffness(&self, max_lambda: f64) -> f64 {
        let f = &self.force_levels_n;
        let shares =
            if self.has_friction_share() && max_lambda > 0.0 { vec![0.0, -max_lambda, max_lambda] } else { vec![0.0] };
        shares
            .into_iter()
            .flat_map(|lambda| {
                (0..self.rows()).flat_map(move |i| {
                    let row = self.row(i, lambda);
                    (1..f.len()).map(move |k| (f[k] - f[k - 1]) / (row.deflection(k) - row.deflection(k - 1)))
                })
            })
            .filter(|k| k.is_finite() && *k > 0.0)
            .fold(0.0, f64::max)
    }

    /// Mean over ξ of the tangent stiffness ∂F/∂δ at the static deflection under F (N/m): what
    /// sets the frequency of small vibrations about that load.
    pub fn mean_tangent_stiffness(&self, force_n: f64) -> f64 {
        let n = self.rows();
        let dx = self.base_pitch_m / n as f64;
        (0..n)
            .map(|i| {
                let xi = (i as f64 + 0.5) * dx;
                self.evaluate(self.static_deflection(force_n, xi), xi).stiffness_n_per_m
            })
            .sum::<f64>()
            / n as f64
    }
}

/// One row of a law at a friction share λ: δ_k + λ·e_k and W*_k + λ·∫e dF.
struct Row<'a> {
    deflection: &'a [f64],
    energy: &'a [f64],
    friction: Option<(&'a [f64], &'a [f64], f64)>,
}

impl Row<'_> {
    fn deflection(&self, k: usize) -> f64 {
        match self.friction {
            Some((e, _, lambda)) => self.deflection[k] + lambda * e[k],
            None => self.deflection[k],
        }
    }

    fn energy(&self, k: usize) -> f64 {
        match self.friction {
            Some((_, w, lambda)) => self.energy[k] + lambda * w[k],
            None => self.energy[k],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear law δ = F/K(ξ) with K varying smoothly: V = ½Kδ² and −∂V/∂ξ = −½K′δ² (closed
    /// form), F = Kδ.
    #[test]
    fn linear_table_reproduces_the_linear_law() {
        let (n, pitch) = (64, 0.02);
        let k = |xi: f64| 2e8 * (1.0 + 0.3 * (2.0 * std::f64::consts::PI * xi / pitch).sin());
        let levels: Vec<f64> = (0..=8).map(|i| 1000.0 * i as f64).collect();
        let mut rows = Vec::new();
        for i in 0..n {
            let xi = pitch * i as f64 / n as f64;
            rows.extend(levels.iter().map(|f| f / k(xi)));
        }
        let law = MeshLaw::new(pitch, levels, rows);
        let xi = 3.0 * pitch / n as f64; // on a row: exact
        let delta = 2.5e-5;
        let m = law.evaluate(delta, xi);
        assert!((m.force_n - k(xi) * delta).abs() < 1e-9 * m.force_n);
        assert!((m.potential_j - 0.5 * k(xi) * delta * delta).abs() < 1e-12);
        // Between rows, the energy and the roll force are consistent: −∂V/∂ξ by central difference.
        let xi = 3.4 * pitch / n as f64;
        let h = 1e-9;
        let numeric = -(law.evaluate(delta, xi + h).potential_j - law.evaluate(delta, xi - h).potential_j) / (2.0 * h);
        let m = law.evaluate(delta, xi);
        assert!(
            (numeric - m.roll_force_n).abs() < 1e-6 * m.roll_force_n.abs().max(1.0),
            "{numeric} vs {}",
            m.roll_force_n
        );
        // And F = ∂V/∂δ.
        let dv = (law.evaluate(delta + 1e-10, xi).potential_j - law.evaluate(delta - 1e-10, xi).potential_j) / 2e-10;
        assert!((dv - m.force_n).abs() < 1e-5 * m.force_n);
    }
}

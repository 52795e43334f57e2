//! The reference solver: Newton–Raphson on every unknown of the reduced pair — r_b1θ₁ and both
//! gears' reduced coordinates, n = 1 + n₁ + n₂ — with a dense LU of the whole Jacobian per
//! iteration and a backtracking line search on the relative force residual. Exact and slow (its
//! cost grows as n³ while only the contact forces are unknown); kept to test the condensed solver
//! against, and as the "before" of the baseline's timing.

use super::{rigid_guess, Element, Equilibrium, Law, StaticModel, WarmStart};
use nalgebra::{DMatrix, DVector};

/// Relative residual at which Newton stops (torque balance over T₁/r_b1, the gears' balance
/// over the size of their contact loads).
const FORCE_TOLERANCE: f64 = 1e-9;
const MAX_NEWTON: usize = 100;

impl StaticModel<'_> {
    pub(super) fn dense_equilibrium(
        &self,
        elements: &mut [Element],
        te_ref: f64,
        target: f64,
        warm: &mut WarmStart,
    ) -> Result<Equilibrium, String> {
        let (n1, n2) = (self.gears[0].size(), self.gears[1].size());
        let n = 1 + n1 + n2;
        let mut y = DVector::<f64>::zeros(n);
        match &warm.reduced {
            // Keep q; the contact search was re-linearized at the new angle.
            Some(q) => {
                y.as_mut_slice()[1..1 + n1].copy_from_slice(&q[0]);
                y.as_mut_slice()[1 + n1..].copy_from_slice(&q[1]);
            }
            None => y[0] = rigid_guess(elements, target)?,
        }
        // Residual, its scale (the size of the contact loads) and, if asked, the Jacobian.
        type Evaluation = (DVector<f64>, f64, Option<DMatrix<f64>>);
        let evaluate = |y: &DVector<f64>, elements: &mut [Element], jac: bool| -> Result<Evaluation, String> {
            let q = [&y.as_slice()[1..1 + n1], &y.as_slice()[1 + n1..]];
            let mut load_norm = 0.0;
            let mut r = DVector::zeros(n);
            r[0] = target;
            for i in 0..2 {
                let k = &self.gears[i].stiffness;
                let off = if i == 0 { 1 } else { 1 + n1 };
                let m = k.nrows();
                for a in 0..m {
                    r[off + a] = (0..m).map(|b| k[(a, b)] * q[i][b]).sum();
                }
            }
            let mut jm = if jac { Some(DMatrix::zeros(n, n)) } else { None };
            if let Some(j) = jm.as_mut() {
                for i in 0..2 {
                    let k = &self.gears[i].stiffness;
                    let off = if i == 0 { 1 } else { 1 + n1 };
                    for a in 0..k.nrows() {
                        for b in 0..k.ncols() {
                            j[(off + a, off + b)] = k[(a, b)];
                        }
                    }
                }
            }
            for e in elements.iter_mut() {
                let alpha = e.alpha0 + e.arm * y[0] + super::dot(&e.gap[0], q[0]) + super::dot(&e.gap[1], q[1]);
                let (force, slope) = e.force(alpha)?;
                e.result.force_n = force;
                e.result.penetration_m = alpha;
                if let Law::Hertz { contact, geometry } = &e.law {
                    if force > 0.0 {
                        let beta = contact.half_width(force);
                        e.result.half_width_m = beta;
                        if let Some(shares) = self.hertz_band_shares(geometry, beta) {
                            e.load = [
                                self.load_row(0, &shares[0], e.friction_per_normal),
                                self.load_row(1, &shares[1], e.friction_per_normal),
                            ];
                            e.load_shares = shares;
                        }
                    }
                }
                if force == 0.0 && slope == 0.0 {
                    continue;
                }
                r[0] -= force * e.torque_arm;
                for i in 0..2 {
                    let off = if i == 0 { 1 } else { 1 + n1 };
                    for (a, b) in e.load[i].iter().enumerate() {
                        r[off + a] -= force * b;
                        load_norm += (force * b).powi(2);
                    }
                }
                if let Some(j) = jm.as_mut() {
                    // ∂/∂y of (−s·P, −P·b): the gradient of α is (s, g₁, g₂).
                    let grad: Vec<(usize, f64)> = std::iter::once((0, e.arm))
                        .chain(e.gap[0].iter().enumerate().map(|(a, v)| (1 + a, *v)))
                        .chain(e.gap[1].iter().enumerate().map(|(a, v)| (1 + n1 + a, *v)))
                        .collect();
                    let rows: Vec<(usize, f64)> = std::iter::once((0, e.torque_arm))
                        .chain(e.load[0].iter().enumerate().map(|(a, v)| (1 + a, *v)))
                        .chain(e.load[1].iter().enumerate().map(|(a, v)| (1 + n1 + a, *v)))
                        .collect();
                    for &(ra, va) in &rows {
                        for &(cb, vb) in &grad {
                            j[(ra, cb)] -= slope * va * vb;
                        }
                    }
                }
            }
            Ok((r, load_norm.sqrt(), jm))
        };
        let merit = |r: &DVector<f64>, scale: f64| {
            (r[0] / target).powi(2) + r.rows(1, n - 1).norm_squared() / scale.max(f64::MIN_POSITIVE).powi(2)
        };
        for iterations in 1..=MAX_NEWTON {
            let (r, scale, j) = evaluate(&y, elements, true)?;
            let current = merit(&r, scale);
            let j = j.expect("Jacobian requested");
            let step = j.lu().solve(&(-&r)).ok_or("singular Jacobian in the static contact solve")?;
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..40 {
                let trial = &y + &step * t;
                if let Ok((rt, st, _)) = evaluate(&trial, elements, false) {
                    if merit(&rt, st) < current || t < 1e-6 {
                        y = trial;
                        accepted = true;
                        break;
                    }
                }
                t *= 0.5;
            }
            if !accepted {
                return Err("line search failed".into());
            }
            let (r, scale, _) = evaluate(&y, elements, false)?;
            let small_step = (step[0] * t).abs() <= 1e-9 * (te_ref + y[0]).abs().max(1e-9);
            if merit(&r, scale).sqrt() <= FORCE_TOLERANCE && small_step {
                let reduced = [y.as_slice()[1..1 + n1].to_vec(), y.as_slice()[1 + n1..].to_vec()];
                warm.reduced = Some(reduced.clone());
                return Ok(Equilibrium { te_offset_m: y[0], reduced, iterations });
            }
        }
        Err(format!("static contact did not converge in {MAX_NEWTON} Newton iterations"))
    }
}

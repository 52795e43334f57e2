//! The quasi-static condensation of the stiff coordinates (issue 24's "step set by the physics").
//!
//! Two groups of the reduced pair's coordinates carry no physics a drivetrain resolves, yet bound
//! an explicit step:
//!
//! - **the contact shapes η_Ψ** against the Hertz contact (30–100 kHz on the default spur pair):
//!   the static residual of the tooth's local deflection, whose dynamics the fixed-interface
//!   modes Φ already carry up to their highest frequency;
//! - **the hub direction**: the bore is the floating frame and, alone, carries 1–2 % of the
//!   gear's inertia, so the bore rings against the rim at 40–60 kHz;
//! - **the body modes above a cut-off**, 3 × the mesh mode's 2-DOF estimate under an explicit
//!   integrator (`BODY_CUTOFF_PER_MESH_MODE`; 9.1 kHz on the default spur pair, whose modes reach
//!   24 kHz), 6 × under the default discrete gradient (`IMPLICIT_BODY_CUTOFF_PER_MESH_MODE`):
//!   they respond quasi-statically to everything at or below the mesh mode.
//!
//! Both are made quasi-static: their inertia is dropped and, at every evaluation of the
//! right-hand side, they take the values at which the forces on them balance (Newton's method
//! with the contact's tangent stiffness, from the last solution). What is integrated is the
//! slow part, in the gear's mean-axis frame: per gear the angle φ = θ + bᵀη_Φ/J (b = (Gx)ᵀMΦ,
//! J the rigid inertia at the bore; `PmorDynamics::port`) and the body-mode coordinates ξ in
//! the complement of the fast body directions F (the hub direction b̂ = b/|b| on the retained
//! modes, and the condensed modes), η_Φ = Q·ξ + F·z_Φ. In these coordinates the kinetic energy
//! with ż_Φ = η̇_Ψ = 0 is ½Jφ̇² + ½ξ̇ᵀ·Qᵀ(M_ΦΦ − bbᵀ/J)Q·ξ̇: a constant mass matrix, so no Gram
//! products, no quadratic velocity terms.
//!
//! The system stays Lagrangian (a degenerate one: T independent of ż), so energy stays the
//! referee: E = T + U + W with the fast coordinates at their equilibrium, and the external
//! torque, which acts at the bore θ = φ − bᵀ(Qξ + F·z_Φ)/J, does the work τ·Δθ. When a master
//! changes a torque between calls (a step load: inputs are held over a communication step) the
//! fast coordinates move at once to the new equilibrium, the minimum of U − τ_new·θ. The torque
//! does τ_new·Δθ on that move and U rises by ΔU ≤ τ_new·Δθ; the difference, what the step load
//! would set ringing in the fast modes, is booked as dissipated. (The trapezoid ½(τ_old +
//! τ_new)·Δθ, booked before, is the reversible work, exact only where θ is linear in τ: with the
//! contact's nonlinearity the energy-conserving integrator's soak showed it creating 3e-5 of
//! the energy in play at a load reversal.)
//!
//! Damping acts as in the full pair, on every coordinate's rate: the fast coordinates have no
//! velocity of their own, but they follow the slow motion through their equilibrium, so their
//! rate is ż = (∂z/∂y)·ẏ. The modal damping of Φ and the mesh damper see η̇_Φ = Q·ξ̇ + F·ż_Φ, the
//! shapes' damping D_Ψ sees η̇_Ψ, and what they load the fast coordinates with is carried onto
//! the slow motion through the equilibrium's tangent (`damp_the_fast_motion`; issue 38: without
//! the shapes' rate the mesh mode lost the full pair's shape damping, without the condensed body
//! modes' rate the mesh damper damped it 8–20 % more than in the full pair at the same c). Tooth
//! friction is taken the same way (issue 42): the flanks slide with every coordinate's rate, and
//! its load on the fast coordinates (the teeth bent along the flank) reaches the slow motion
//! through the tangent, to first order in μ.
//!
//! The hub direction is condensed only where its free frequency (the pencil (Λ, M_ΦΦ − bbᵀ/J) on
//! the retained modes) lies above the cut-off: a bore given a shaft's inertia (`inertia_i` above
//! the FE value) has a physical hub mode, which stays.

pub use super::condensation::*;
use super::contact::{section_damper_force_n, GearPose, SectionRows};
use super::contact_law::contact_loads;
use super::equations::shape_stiffness_of_interval;
pub use super::model::Condensation;
use super::{Layout, PmorDynamics, PmorOutputs, PmorState};
use nalgebra::{DMatrix, DVector};

/// The forces at one (slow, fast) point.
struct Evaluation {
    /// The force on the fast coordinates (zero at their equilibrium), both gears stacked.
    residual: DVector<f64>,
    /// Its tangent stiffness −∂residual/∂z (elastic and contact; the contact's angle terms
    /// left out: Newton's matrix needs to be close, not exact).
    tangent: Option<FastTangent>,
    /// What the slow forces' change with z is made of (with the tangent): per loaded section its
    /// row in the fast coordinates (the rows in the slow ones are `outputs.contact.sections`),
    /// and per gear K′_Ψη_Ψ.
    fast_rows: Vec<DVector<f64>>,
    shape_slope: [DVector<f64>; 2],
    /// The slow accelerations (φ̈, ξ̈) per gear, in the layout's q order.
    acceleration: Vec<f64>,
    /// The dissipation power (W): modal damping and the mesh damper on the slow motion.
    dissipation_w: f64,
    /// Per gear, the shapes' damping D_Ψ(ϑ) at this pose (n_t × n_t; empty where undamped).
    shape_damping: [DMatrix<f64>; 2],
    /// The damping forces (modal, the mesh damper's and tooth friction's, from the slow motion's
    /// rates; the sign of D·q̇) on the fast coordinates: in z_Φ what the slow projection leaves,
    /// on η_Ψ friction's (the teeth bent along the flank). Carried onto the slow motion through
    /// the equilibrium (`damp_the_fast_motion`).
    fast_damping: DVector<f64>,
    outputs: PmorOutputs,
}

impl<'a> PmorDynamics<'a> {
    pub fn condensed(&self) -> Option<&QuasiStatic> {
        self.quasi_static.as_ref()
    }

    /// Per gear: η_Φ, η_Ψ, θ, and (θ̇, η̇_Φ) of the slow motion, from y and the fast z.
    fn expand(&self, qs: &QuasiStatic, l: &Layout, y: &[f64], i: usize, z: &[f64]) -> (Vec<f64>, f64, Vec<f64>) {
        let g = &self.model.gears[i];
        let sp = &qs.splits[i];
        let n_x = sp.slow_size();
        let n_k = g.modes();
        let mut eta_phi = Vec::with_capacity(g.elastic_size());
        eta_phi.resize(n_k, 0.0);
        sp.add_slow(&y[l.q(i) + 1..l.q(i) + 1 + n_x], &mut eta_phi);
        let n_f = sp.fast_body_size();
        for (column, &z_c) in sp.fast_columns.iter().zip(&z[..n_f]) {
            for &(j, f) in column {
                eta_phi[j] += f * z_c;
            }
        }
        let theta = y[l.q(i)] - sp.b.iter().zip(&eta_phi).map(|(b, e)| b * e).sum::<f64>() / sp.inertia_kgm2;
        let mut eta = eta_phi;
        eta.extend_from_slice(&z[n_f..]);
        (eta, theta, self.slow_body_velocity(qs, l, y, i))
    }

    /// Gear i's (θ̇, η̇_Φ) of the slow motion alone (the fast coordinates held): η̇_Φ = Q·ξ̇,
    /// θ̇ = φ̇ − bᵀη̇_Φ/J.
    fn slow_body_velocity(&self, qs: &QuasiStatic, l: &Layout, y: &[f64], i: usize) -> Vec<f64> {
        let sp = &qs.splits[i];
        let n_x = sp.slow_size();
        let mut velocity = vec![0.0; 1 + self.model.gears[i].modes()];
        sp.add_slow(&y[l.v(i) + 1..l.v(i) + 1 + n_x], &mut velocity[1..]);
        velocity[0] = y[l.v(i)] - sp.b.iter().zip(&velocity[1..]).map(|(b, v)| b * v).sum::<f64>() / sp.inertia_kgm2;
        velocity
    }

    /// The forces with the slow state y and the fast coordinates z.
    fn evaluate(
        &self,
        qs: &QuasiStatic,
        y: &[f64],
        z: &[Vec<f64>; 2],
        anchor: [i64; 2],
        torques: [f64; 2],
        tangent: bool,
    ) -> Result<Evaluation, String> {
        let (evaluations, solves) = qs.counts.get();
        qs.counts.set((evaluations + 1, solves));
        let l = self.layout();
        let model = self.model;
        let (e0, e1) = (self.expand(qs, &l, y, 0, &z[0]), self.expand(qs, &l, y, 1, &z[1]));
        let expanded = [e0, e1];
        let stencils = [self.stencil(0, anchor[0], expanded[0].1)?, self.stencil(1, anchor[1], expanded[1].1)?];
        let rates = self.mesh_damping_n_s_per_m > 0.0 || self.friction.is_some();
        let poses = [0, 1].map(|i| GearPose {
            theta: expanded[i].1,
            anchor: anchor[i],
            stencil: stencils[i],
            eta: &expanded[i].0,
            velocity: if rates { &expanded[i].2 } else { &[] },
        });
        let restage = |i: usize, theta: f64| self.stencil(i, anchor[i], theta);
        let contact = contact_loads(
            model,
            self.place,
            [&poses[0], &poses[1]],
            &restage,
            self.loading,
            self.mesh_damping_n_s_per_m,
            self.friction,
            tangent,
        )?;
        let n_z = [z[0].len(), z[1].len()];
        let mut residual = DVector::zeros(n_z[0] + n_z[1]);
        let mut tangent_matrix = tangent.then(FastTangent::new);
        let mut fast_rows = Vec::new();
        let mut shape_slope = [DVector::zeros(0), DVector::zeros(0)];
        let mut acceleration = vec![0.0; l.n_q[0] + l.n_q[1]];
        let mut out = PmorOutputs { damping_force: vec![0.0; l.n_q[0] + l.n_q[1]], ..Default::default() };
        let mut dissipation = contact.damper_power_w + contact.friction_power_w;
        let mut shape_damping = [DMatrix::zeros(0, 0), DMatrix::zeros(0, 0)];
        let mut fast_damping = DVector::zeros(n_z[0] + n_z[1]);
        for i in 0..2 {
            let g = &model.gears[i];
            let sp = &qs.splits[i];
            let (n_k, n_t) = (g.modes(), g.shapes);
            let ratio = self.damping[i].shapes_ratio;
            if ratio > 0.0 && n_t > 0 {
                // D_Ψ(ϑ) = 2ζ·((1 − p)·D_s + p·D_{s+1}), as the full pair's (`equations::gear_terms`).
                let st = &stencils[i];
                let (lo, hi) = (&g.shape_damping_roots[st.a0 + 1], &g.shape_damping_roots[st.a0 + 2]);
                let p = st.fraction;
                shape_damping[i] =
                    DMatrix::from_fn(n_t, n_t, |r, c| 2.0 * ratio * ((1.0 - p) * lo[(r, c)] + p * hi[(r, c)]));
            }
            let (eta, theta, velocity) = &expanded[i];
            let (eta_phi, eta_psi) = eta.split_at(n_k);
            let z_off = if i == 0 { 0 } else { n_z[0] };
            // The elastic forces in (θ, η_Φ, η_Ψ): the contact's (its damper part removed), the
            // bodies' and the external torque.
            let elastic_contact = |k: usize| contact.force[i][k] + contact.damping_force[i][k];
            let mut terms = self.terms[i].borrow_mut();
            let terms = &mut *terms;
            let block = self.shape_stiffness_block(i, stencils[i].a0);
            shape_stiffness_of_interval(&block, &stencils[i], &mut terms.k_psi, &mut terms.dk_psi);
            let psi = DVector::from_column_slice(eta_psi);
            let k_psi_eta = &terms.k_psi * &psi;
            let f_theta = elastic_contact(0) + torques[i] - 0.5 * psi.dot(&(&terms.dk_psi * &psi));
            let f_phi = DVector::from_fn(n_k, |j, _| elastic_contact(1 + j) - g.eigenvalues[j] * eta_phi[j]);
            // The slow motion's damping forces in (θ, η_Φ): the damper's and the modal one.
            let eta_phi_dot = &velocity[1..];
            let modal = DVector::from_fn(n_k, |j, _| {
                2.0 * self.damping[i].modes_ratio * g.eigenvalues[j].sqrt() * eta_phi_dot[j]
            });
            let d_theta = contact.damping_force[i][0];
            let d_phi = DVector::from_fn(n_k, |j, _| contact.damping_force[i][1 + j] + modal[j]);
            dissipation += modal.iter().zip(eta_phi_dot).map(|(f, v)| f * v).sum::<f64>();
            // To the slow coordinates: on φ the θ force, on ξ Qᵀ(f_Φ − b·f_θ/J).
            let to_xi = |f_t: f64, f_p: &DVector<f64>| sp.force_on_slow(f_t, f_p.as_slice());
            let q = l.q(i);
            acceleration[q] = (f_theta - d_theta) / sp.inertia_kgm2;
            let mut xi_acc = to_xi(f_theta - d_theta, &(&f_phi - &d_phi));
            sp.xi_acceleration(&mut xi_acc);
            acceleration[q + 1..q + l.n_q[i]].copy_from_slice(xi_acc.as_slice());
            out.damping_force[q] = d_theta;
            out.damping_force[q + 1..q + l.n_q[i]].copy_from_slice(to_xi(d_theta, &d_phi).as_slice());
            // The fast coordinates' residual: Fᵀf_Φ − (Fᵀb/J)·f_θ on z_Φ, f_Ψ on η_Ψ.
            let mut r = z_off;
            let n_f = sp.fast_body_size();
            for c in 0..n_f {
                residual[r + c] = sp.fast_dot(c, f_phi.as_slice()) - sp.bore_turn[c] * f_theta;
                fast_damping[r + c] = sp.fast_dot(c, d_phi.as_slice()) - sp.bore_turn[c] * d_theta;
            }
            r += n_f;
            for m in 0..n_t {
                residual[r + m] = elastic_contact(1 + n_k + m) - k_psi_eta[m];
                fast_damping[r + m] = contact.damping_force[i][1 + n_k + m];
            }
            if let Some(t) = tangent_matrix.as_mut() {
                t.body.extend((0..n_f).map(|a| (z_off + a, sp.fast_stiffness[a])));
                if n_t > 0 {
                    let k = DMatrix::from_fn(n_t, n_t, |a, b| 0.5 * (terms.k_psi[(a, b)] + terms.k_psi[(b, a)]));
                    let factor = k.cholesky().ok_or("the contact shapes' stiffness K_Ψ is not positive definite")?;
                    t.shapes.push((z_off + n_f, factor.inverse()));
                }
            }
            if tangent {
                shape_slope[i] = &terms.dk_psi * &psi;
            }
            // Energies: T of the slow motion, U of the bodies and shapes.
            let v = &y[l.v(i)..l.v(i) + l.n_q[i]];
            let xi_dot = DVector::from_column_slice(&v[1..]);
            out.kinetic_j += 0.5 * sp.inertia_kgm2 * v[0] * v[0] + 0.5 * xi_dot.dot(&(&sp.xi_mass * &xi_dot));
            out.elastic_j += 0.5 * psi.dot(&k_psi_eta)
                + 0.5 * (0..n_k).map(|j| g.eigenvalues[j] * eta_phi[j] * eta_phi[j]).sum::<f64>();
            out.bore_theta[i] = *theta;
        }
        if tangent {
            // The sections' rows g in the fast coordinates (Newton's Σ k_s·g gᵀ).
            for section in &contact.sections {
                let mut row = DVector::zeros(n_z[0] + n_z[1]);
                for i in 0..2 {
                    let sp = &qs.splits[i];
                    let n_k = model.gears[i].modes();
                    let rows = &section.rows[i];
                    let mut r = if i == 0 { 0 } else { n_z[0] };
                    for c in 0..sp.fast_body_size() {
                        row[r] = sp.fast_dot(c, &rows[1..]) - sp.bore_turn[c] * rows[0];
                        r += 1;
                    }
                    for m in 0..model.gears[i].shapes {
                        row[r + m] = rows[1 + n_k + m];
                    }
                }
                fast_rows.push(row);
            }
        }
        out.contact_j = contact.potential_j;
        out.contact = contact;
        Ok(Evaluation {
            residual,
            tangent: tangent_matrix,
            fast_rows,
            shape_slope,
            acceleration,
            dissipation_w: dissipation,
            shape_damping,
            fast_damping,
            outputs: out,
        })
    }

    /// The slow accelerations and the mesh force as they follow a Newton step Δz of the fast
    /// coordinates, to first order: Δf = −Σ_s k_s·(g_s·Δz)·r_s over the loaded sections (r_s the section's row in
    /// (θ, η_Φ), mapped to (φ, ξ) as every force is), the fast body coordinates' −QᵀΛF·Δz_Φ on ξ, and
    /// −(K′_Ψη_Ψ)·Δη_Ψ on φ.
    fn shift_slow_forces(&self, qs: &QuasiStatic, e: &mut Evaluation, dz: &DVector<f64>) {
        let l = self.layout();
        let n_z0 = qs.fast.borrow()[0].len();
        // The mesh force output follows too (each section's force by k_s·(g_s·Δz)): the step
        // hands its last evaluation to the FMU's outputs (`PmorDynamics::advance_knowing`).
        for (section, row) in e.outputs.contact.sections.iter().zip(&e.fast_rows) {
            e.outputs.contact.normal_force_n += section.flank_sign * section.stiffness_n_per_m * row.dot(dz);
        }
        for i in 0..2 {
            let g = &self.model.gears[i];
            let sp = &qs.splits[i];
            let n_k = g.modes();
            let z_off = if i == 0 { 0 } else { n_z0 };
            // The force change in (θ, η_Φ).
            let mut f_theta = 0.0;
            let mut f_phi = DVector::<f64>::zeros(n_k);
            for (section, row) in e.outputs.contact.sections.iter().zip(&e.fast_rows) {
                let df = section.stiffness_n_per_m * row.dot(dz);
                let rows = &section.rows[i];
                f_theta -= df * rows[0];
                for j in 0..n_k {
                    f_phi[j] -= df * rows[1 + j];
                }
            }
            let mut r = z_off;
            let n_f = sp.fast_body_size();
            for c in 0..n_f {
                for &(j, f) in &sp.fast_columns[c] {
                    f_phi[j] -= g.eigenvalues[j] * f * dz[r + c];
                }
                // The bore moves with the fast body coordinates: θ = φ − bᵀ(Qξ + Fz)/J.
                e.outputs.bore_theta[i] -= sp.bore_turn[c] * dz[r + c];
            }
            r += n_f;
            f_theta -= (0..g.shapes).map(|m| e.shape_slope[i][m] * dz[r + m]).sum::<f64>();
            let q = l.q(i);
            e.acceleration[q] += f_theta / sp.inertia_kgm2;
            let mut xi_acc = sp.force_on_slow(f_theta, f_phi.as_slice());
            sp.xi_acceleration(&mut xi_acc);
            for (a, d) in e.acceleration[q + 1..q + l.n_q[i]].iter_mut().zip(xi_acc.iter()) {
                *a += d;
            }
        }
    }

    /// The fast coordinates' equilibrium at slow state y (Newton from the last solution, with
    /// step halving where a trial leaves the contact law's range), and the forces there.
    fn solve_fast(
        &self,
        qs: &QuasiStatic,
        y: &[f64],
        anchor: [i64; 2],
        torques: [f64; 2],
    ) -> Result<Evaluation, String> {
        let n_q = y.len() / 2 - 1;
        let positions = &y[..n_q];
        let (evaluations, solves) = qs.counts.get();
        qs.counts.set((evaluations, solves + 1));
        let mut z = qs.fast.borrow().clone();
        if let Some(p) = qs.prediction.borrow().as_ref() {
            // The tangent of z(y) at the last solve.
            let mut force = DVector::zeros(z[0].len() + z[1].len());
            for i in 0..2 {
                let offset = if i == 0 { 0 } else { z[0].len() };
                let turn = &qs.splits[i].bore_turn;
                for c in 0..turn.len() {
                    force[offset + c] -= turn[c] * (torques[i] - p.torques[i]);
                }
            }
            let moved: Vec<f64> = positions.iter().zip(&p.positions).map(|(y, y0)| y - y0).collect();
            add_fast_load_of_slow_move(&p.fast_rows, &p.stiffness, &p.slow_rows, &moved, &mut force);
            let dz = p.tangent.solve(&force, &p.fast_rows, &p.stiffness)?;
            let n0 = z[0].len();
            z[0].iter_mut().enumerate().for_each(|(k, v)| *v += dz[k]);
            z[1].iter_mut().enumerate().for_each(|(k, v)| *v += dz[n0 + k]);
        }
        let mut e = match self.evaluate(qs, y, &z, anchor, torques, true) {
            Ok(e) => e,
            Err(_) => {
                // The tangent's prediction left the contact law's range: from the last
                // solution itself, and failing that (a pose far from it) from no deformation.
                z = qs.fast.borrow().clone();
                match self.evaluate(qs, y, &z, anchor, torques, true) {
                    Ok(e) => e,
                    Err(_) => {
                        z.iter_mut().for_each(|v| v.fill(0.0));
                        self.evaluate(qs, y, &z, anchor, torques, true)?
                    }
                }
            }
        };
        let keep = |z: [Vec<f64>; 2]| *qs.fast.borrow_mut() = z;
        let shifted = |z: &[Vec<f64>; 2], dz: &DVector<f64>, t: f64| {
            let mut trial = z.clone();
            let n0 = trial[0].len();
            trial[0].iter_mut().enumerate().for_each(|(k, v)| *v += t * dz[k]);
            trial[1].iter_mut().enumerate().for_each(|(k, v)| *v += t * dz[n0 + k]);
            trial
        };
        // Newton's step and decrement ΔzᵀKΔz = Δzᵀr at an evaluation.
        let newton = |e: &mut Evaluation| -> Result<(DVector<f64>, f64), String> {
            let k = e.tangent.as_ref().expect("asked for");
            let stiffness: Vec<f64> = e.outputs.contact.sections.iter().map(|s| s.stiffness_n_per_m).collect();
            let dz = k.solve(&e.residual, &e.fast_rows, &stiffness)?;
            let decrement = dz.dot(&e.residual);
            Ok((dz, decrement))
        };
        let (mut dz, mut decrement) = newton(&mut e)?;
        let (mut lowest, mut since_lowest) = (f64::INFINITY, 0);
        for _ in 0..NEWTON_ITERATIONS {
            let potential = e.outputs.elastic_j + e.outputs.contact_j;
            if decrement.abs() < lowest {
                (lowest, since_lowest) = (decrement.abs(), 0);
            } else {
                since_lowest += 1;
            }
            let stalled = since_lowest >= STALL_ITERATIONS
                && decrement.abs() <= 2.0 * lowest
                && decrement.abs() <= STALL_RELATIVE_DECREMENT * potential;
            let tight = decrement.abs() <= STEP_RELATIVE_DECREMENT * potential + NEWTON_FLOOR_J;
            let at_predictor =
                qs.at_predictor.get() && decrement.abs() <= PREDICTOR_RELATIVE_DECREMENT * potential + NEWTON_FLOOR_J;
            if qs.stepping.get() && (tight || at_predictor || stalled) {
                qs.last_solve_tight.set(tight);
                // The last step without a new evaluation: the slow forces follow to first order,
                // and so does the stored energy: U changes by ∇U·Δz + ½ΔzᵀKΔz, with ∇U = −r + τ·∂θ/∂z
                // and KΔz = r, i.e. by τ·Δθ − ½·decrement (else U and θ would disagree by τ·Δθ,
                // first order in Δz, in every energy balance that reads them).
                let bore_before = e.outputs.bore_theta;
                self.shift_slow_forces(qs, &mut e, &dz);
                e.outputs.elastic_j += torques[0] * (e.outputs.bore_theta[0] - bore_before[0])
                    + torques[1] * (e.outputs.bore_theta[1] - bore_before[1])
                    - 0.5 * decrement;
                keep(shifted(&z, &dz, 1.0));
                let slow_rows = self.slow_rows(qs, &e);
                self.damp_the_fast_motion(qs, y, &mut e, &slow_rows)?;
                self.remember(qs, positions, torques, &mut e, slow_rows);
                return Ok(e);
            }
            if decrement.abs() <= NEWTON_RELATIVE_DECREMENT * potential + NEWTON_FLOOR_J {
                keep(z);
                let slow_rows = self.slow_rows(qs, &e);
                self.damp_the_fast_motion(qs, y, &mut e, &slow_rows)?;
                self.remember(qs, positions, torques, &mut e, slow_rows);
                return Ok(e);
            }
            // The step, halved while the decrement (the residual's size in K⁻¹'s norm) does not
            // fall: at a contact's onset the stiffness jumps and full steps can cycle, a section
            // switching on and off. A step that leaves the contact law's range is halved too.
            // Where no halving down to 1/64 lowers it, the lowest tried is taken.
            let mut best: Option<(f64, [Vec<f64>; 2], Evaluation, DVector<f64>)> = None;
            let mut failure = None;
            let mut t = 1.0;
            while t >= 1.0 / 64.0 {
                let trial = shifted(&z, &dz, t);
                match self.evaluate(qs, y, &trial, anchor, torques, true) {
                    Ok(mut next) => {
                        let (next_dz, next_decrement) = newton(&mut next)?;
                        let lower = next_decrement.abs() <= (1.0 - 1e-4 * t) * decrement.abs();
                        if lower || best.as_ref().map_or(true, |b| next_decrement.abs() < b.0) {
                            best = Some((next_decrement.abs(), trial, next, next_dz));
                        }
                        if lower {
                            break;
                        }
                    }
                    Err(err) => failure = Some(err),
                }
                t *= 0.5;
            }
            let Some((next_decrement, trial, next, next_dz)) = best else {
                return Err(failure.unwrap_or_else(|| "no Newton step could be evaluated".into()));
            };
            (z, e, dz, decrement) = (trial, next, next_dz, next_decrement);
        }
        let last_decrement = decrement;
        Err(format!(
            "the quasi-static shapes found no equilibrium in {NEWTON_ITERATIONS} Newton iterations (θ = {:?} rad; last decrement {last_decrement:e} J against a potential of {:e} J)",
            e.outputs.bore_theta,
            e.outputs.elastic_j + e.outputs.contact_j
        ))
    }

    /// Per loaded section, its row r_s = ∂α_s/∂y in the slow positions (φ, ξ per gear), mapped as
    /// a force is: a force P along the section acts on the slow coordinates as P·r_s.
    fn slow_rows(&self, qs: &QuasiStatic, e: &Evaluation) -> Vec<Vec<f64>> {
        let l = self.layout();
        let n_q = l.n_q[0] + l.n_q[1];
        e.outputs
            .contact
            .sections
            .iter()
            .map(|section| {
                let mut row = vec![0.0; n_q];
                for i in 0..2 {
                    let n_k = self.model.gears[i].modes();
                    let rows = &section.rows[i];
                    let q = l.q(i);
                    row[q] = rows[0];
                    qs.splits[i].force_on_slow_into(rows[0], &rows[1..1 + n_k], &mut row[q + 1..q + l.n_q[i]]);
                }
                row
            })
            .collect()
    }

    /// The damping of the fast coordinates' motion, carried onto the slow motion. The fast
    /// coordinates are quasi-static, so their rate follows the slow velocity v through the
    /// equilibrium (the implicit function theorem, as `Prediction`): K·ż = −Σ_s k_s·g_s·(r_s·v).
    /// Two dampings and tooth friction see that rate in the full pair:
    ///
    /// - **the shapes' D_Ψ** (the build's `shape_damping_ratio`) on η̇_Ψ;
    /// - **the bodies' damping** — the condensed body modes' modal damping and the mesh damper,
    ///   whose approach rate is made of θ̇ and every η̇_Φ, the condensed modes' too: with
    ///   η̇_Φ = Q·ξ̇ + F·ż_Φ and θ̇ = φ̇ − bᵀη̇_Φ/J. `evaluate` damps the slow rates alone; here
    ///   the fast rates' share is added (the mesh damper per section recomputed with the whole
    ///   rate, still never pulling).
    ///
    /// - **tooth friction** (`contact::apply_tooth_friction`), whose sliding is made of θ̇ and
    ///   every elastic rate along the flank: the fast rates' share is added per section, f taken
    ///   at the whole sliding, and its load on η_Ψ and the fast body coordinates carried as the
    ///   damping's is (issue 42: the teeth bent along the flank, to first order in μ).
    ///
    /// A damping force d (the sign of D·q̇) acts on the slow coordinates by virtual work: its
    /// slow projection directly, its fast projection through the same tangent,
    /// f = −(∂z/∂y)ᵀd_z = Σ_s r_s·k_s·g_s·K⁻¹·d_z. So the power taken is the damping's own, ≥ 0.
    /// Issue 38: without the shapes' damping the mesh mode kept only the body modes' share
    /// (linearized ζ 0.05–0.09 % on the Kurokawa spur pair without a mesh damper, 0.32–0.41 %
    /// in the full pair); without the condensed modes' rate the mesh damper saw a larger
    /// approach rate than the full pair's and damped the mesh mode 20 % more at the same c
    /// (small helical pair), 1.7–2.1 × more at the 3 × cut-off.
    fn damp_the_fast_motion(
        &self,
        qs: &QuasiStatic,
        y: &[f64],
        e: &mut Evaluation,
        slow_rows: &[Vec<f64>],
    ) -> Result<(), String> {
        let shapes_damped = e.shape_damping.iter().any(|d| d.nrows() > 0);
        let bodies_damped = self.mesh_damping_n_s_per_m > 0.0 || self.damping.iter().any(|d| d.modes_ratio > 0.0);
        let fast_bodies = qs.splits.iter().any(|sp| sp.fast_body_size() > 0);
        let friction = self.friction;
        if !(shapes_damped || (bodies_damped && fast_bodies) || friction.is_some())
            || e.outputs.contact.sections.is_empty()
        {
            return Ok(());
        }
        let Some(tangent) = e.tangent.as_ref() else { return Ok(()) };
        let l = self.layout();
        let n_q = l.n_q[0] + l.n_q[1];
        let velocity = &y[n_q..2 * n_q];
        let stiffness: Vec<f64> = e.outputs.contact.sections.iter().map(|s| s.stiffness_n_per_m).collect();
        let n_z0 = qs.fast.borrow()[0].len();
        let n_z = e.residual.len();
        let mut force = DVector::zeros(n_z);
        add_fast_load_of_slow_move(&e.fast_rows, &stiffness, slow_rows, velocity, &mut force);
        let rate = tangent.solve(&force, &e.fast_rows, &stiffness)?;
        // The damping forces on the fast coordinates (the sign of D·q̇): the bodies' from the
        // slow rates, then what follows.
        let mut damping_force = e.fast_damping.clone();
        let mut power = 0.0;
        // The shapes: D_Ψ·ż on each gear's shape block (the last n_t of its fast coordinates).
        for i in 0..2 {
            let d = &e.shape_damping[i];
            let n_t = d.nrows();
            if n_t == 0 {
                continue;
            }
            let end = if i == 0 { n_z0 } else { n_z };
            let start = end - n_t;
            for a in 0..n_t {
                let f: f64 = (0..n_t).map(|b| d[(a, b)] * rate[start + b]).sum();
                damping_force[start + a] += f;
                power += rate[start + a] * f;
            }
        }
        // The bodies: the fast rates' share of (θ̇, η̇_Φ) per gear, and the damping it adds there.
        let mut on_slow = vec![0.0; n_q];
        if (bodies_damped && fast_bodies) || friction.is_some() {
            let slow_velocity = [self.slow_body_velocity(qs, &l, y, 0), self.slow_body_velocity(qs, &l, y, 1)];
            let mut fast_velocity: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
            let mut body_force: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
            for i in 0..2 {
                let (sp, g) = (&qs.splits[i], &self.model.gears[i]);
                let z_off = if i == 0 { 0 } else { n_z0 };
                let mut v = vec![0.0; 1 + g.modes()];
                for c in 0..sp.fast_body_size() {
                    for &(j, f) in &sp.fast_columns[c] {
                        v[1 + j] += f * rate[z_off + c];
                    }
                    v[0] -= sp.bore_turn[c] * rate[z_off + c];
                }
                // Modal damping is linear in η̇_Φ: its increment is D_Φ·(F·ż_Φ).
                let slow = &slow_velocity[i];
                let mut f = vec![0.0; 1 + g.modes()];
                for j in 0..g.modes() {
                    let d = 2.0 * self.damping[i].modes_ratio * g.eigenvalues[j].sqrt();
                    f[1 + j] = d * v[1 + j];
                    power += d * v[1 + j] * (2.0 * slow[1 + j] + v[1 + j]);
                }
                fast_velocity[i] = v;
                body_force[i] = f;
            }
            // The mesh damper, per section, with the whole approach rate (`contact::apply_mesh_damper`).
            let n_body = [1 + self.model.gears[0].modes(), 1 + self.model.gears[1].modes()];
            let total_stiffness: f64 = stiffness.iter().sum();
            if self.mesh_damping_n_s_per_m > 0.0 && total_stiffness > 0.0 && fast_bodies {
                let damper = |section: &SectionRows, rate: f64| {
                    section_damper_force_n(section, self.mesh_damping_n_s_per_m, total_stiffness, rate)
                };
                let contact = &mut e.outputs.contact;
                for section in contact.sections.iter() {
                    let along = |v: &[Vec<f64>; 2]| -> f64 {
                        (0..2)
                            .map(|i| section.rows[i][..n_body[i]].iter().zip(&v[i]).map(|(r, v)| r * v).sum::<f64>())
                            .sum()
                    };
                    let (slow_rate, fast_rate) = (along(&slow_velocity), along(&fast_velocity));
                    let before = damper(section, slow_rate);
                    let after = damper(section, slow_rate + fast_rate);
                    let added = after - before;
                    power += after * (slow_rate + fast_rate) - before * slow_rate;
                    // The mesh force output includes the damper (`contact_loads`).
                    contact.damper_force_n += section.flank_sign * added;
                    contact.normal_force_n += section.flank_sign * added;
                    for i in 0..2 {
                        for (f, r) in body_force[i].iter_mut().zip(&section.rows[i][..n_body[i]]) {
                            *f += added * r;
                        }
                    }
                }
            }
            // Tooth friction, per section, with the whole sliding (`contact::apply_tooth_friction`):
            // the bodies' fast rates and the shapes' rates along the flank added to the slow
            // motion's. What it adds acts on (θ, η_Φ) with the bodies' forces and on η_Ψ directly.
            if let Some(law) = friction {
                let shapes_at = [qs.splits[0].fast_body_size(), n_z0 + qs.splits[1].fast_body_size()];
                let contact = &mut e.outputs.contact;
                for section in contact.sections.iter() {
                    let s = &section.sliding_rows;
                    let along = |v: &[Vec<f64>; 2]| -> f64 {
                        (0..2).map(|i| s[i][..n_body[i]].iter().zip(&v[i]).map(|(r, v)| r * v).sum::<f64>()).sum()
                    };
                    let shapes_rate: f64 = (0..2)
                        .map(|i| {
                            s[i][n_body[i]..]
                                .iter()
                                .zip(&rate.as_slice()[shapes_at[i]..])
                                .map(|(r, v)| r * v)
                                .sum::<f64>()
                        })
                        .sum();
                    let (slow_rate, fast_rate) = (along(&slow_velocity), along(&fast_velocity) + shapes_rate);
                    let before = law.force_n(section.force_n, slow_rate);
                    let after = law.force_n(section.force_n, slow_rate + fast_rate);
                    let added = after - before;
                    let taken = after * (slow_rate + fast_rate) - before * slow_rate;
                    power += taken;
                    contact.friction_power_w += taken;
                    contact.friction_force_n += added;
                    for i in 0..2 {
                        debug_assert_eq!(s[i].len(), n_body[i] + self.model.gears[i].shapes, "friction's rows");
                        for (f, r) in body_force[i].iter_mut().zip(&s[i][..n_body[i]]) {
                            *f += added * r;
                        }
                        // The mesh torque output (`force` on θ) carries the whole friction.
                        contact.force[i][0] -= added * s[i][0];
                        for (m, r) in s[i][n_body[i]..].iter().enumerate() {
                            damping_force[shapes_at[i] + m] += added * r;
                        }
                    }
                }
            }
            // Each gear's added body force: on the slow coordinates directly, on the fast ones
            // to be carried below.
            for i in 0..2 {
                let sp = &qs.splits[i];
                let z_off = if i == 0 { 0 } else { n_z0 };
                let (f_theta, f_phi) = (body_force[i][0], &body_force[i][1..]);
                let q = l.q(i);
                on_slow[q] -= f_theta;
                let on_xi = sp.force_on_slow(f_theta, f_phi);
                for (o, f) in on_slow[q + 1..q + l.n_q[i]].iter_mut().zip(on_xi.iter()) {
                    *o -= f;
                }
                for c in 0..sp.fast_body_size() {
                    damping_force[z_off + c] += sp.fast_dot(c, f_phi) - sp.bore_turn[c] * f_theta;
                }
            }
        }
        let w = tangent.solve(&damping_force, &e.fast_rows, &stiffness)?;
        for ((g, k), r) in e.fast_rows.iter().zip(&stiffness).zip(slow_rows) {
            let share = k * g.dot(&w);
            on_slow.iter_mut().zip(r).for_each(|(f, r)| *f += share * r);
        }
        for i in 0..2 {
            let sp = &qs.splits[i];
            let q = l.q(i);
            let n = l.n_q[i];
            e.acceleration[q] += on_slow[q] / sp.inertia_kgm2;
            let mut xi_acc = DVector::from_column_slice(&on_slow[q + 1..q + n]);
            sp.xi_acceleration(&mut xi_acc);
            for (a, d) in e.acceleration[q + 1..q + n].iter_mut().zip(xi_acc.iter()) {
                *a += d;
            }
        }
        // Dq̇'s sign: the force the damping takes away.
        for (d, f) in e.outputs.damping_force.iter_mut().zip(&on_slow) {
            *d -= f;
        }
        e.dissipation_w += power;
        Ok(())
    }

    /// The contact's stiffness on the slow coordinates at the last solve, as accelerations
    /// (M⁻¹·A_c, n_q × n_q), with the mesh damper's (M⁻¹·D_c, `slow_mesh_damper_acceleration`;
    /// `None` without a damper); `None` before a solve or without contact. With the fast coordinates
    /// at their equilibrium, the approach of section s is α_s = r_s·y + g_s·z and the fast tangent
    /// K_f = D + Σ k_s g_s g_sᵀ, so dz/dy = −K_f⁻¹ Σ k_t g_t r_tᵀ and the condensed stiffness is the
    /// Schur complement A_c = Σ k_s r_s r_sᵀ − Σ_s Σ_t k_s k_t (g_sᵀK_f⁻¹g_t) r_s r_tᵀ. What the
    /// discrete gradient's Newton matrix needs of the mesh (issue 39: with the bodies' stiffness
    /// alone it converged at (ωh)²/4 per iteration on the mesh mode, four solves a step).
    pub(super) fn slow_contact_accelerations(&self, qs: &QuasiStatic) -> Option<(DMatrix<f64>, Option<DMatrix<f64>>)> {
        let p = qs.prediction.borrow();
        let p = p.as_ref()?;
        if p.stiffness.is_empty() {
            return None;
        }
        let l = self.layout();
        let n_q = l.n_q[0] + l.n_q[1];
        // w_t = K_f⁻¹g_t, shared by the stiffness and the damper.
        let w: Vec<DVector<f64>> = p
            .fast_rows
            .iter()
            .map(|g| p.tangent.solve(g, &p.fast_rows, &p.stiffness))
            .collect::<Result<_, _>>()
            .ok()?;
        // With R the sections' slow rows (S × n_q), k their stiffnesses and C_st = g_sᵀw_t:
        // A_c = (kR)ᵀ·(R − C·(kR)), two dense products.
        let n_s = p.slow_rows.len();
        let r = DMatrix::from_fn(n_s, n_q, |s, j| p.slow_rows[s][j]);
        let kr = DMatrix::from_fn(n_s, n_q, |s, j| p.stiffness[s] * r[(s, j)]);
        let c = DMatrix::from_fn(n_s, n_s, |s, t| p.fast_rows[s].dot(&w[t]));
        let mut a = kr.transpose() * (&r - c * &kr);
        self.slow_accelerations(qs, &mut a);
        let damper = self.slow_mesh_damper_acceleration(qs, p, &w, r);
        a.iter().all(|x| x.is_finite()).then_some((a, damper))
    }

    /// The mesh damper on the slow coordinates at the last solve, as accelerations (M⁻¹·D_c,
    /// n_q × n_q; `None` before a solve or without contact). Section s's damper, c_s (its share of
    /// c, in proportion to its stiffness: `contact::apply_mesh_damper`), acts on its approach rate
    /// from the bodies, which the condensed body modes' rate ż_Φ = (∂z/∂y)_Φ·v is part of
    /// (`damp_the_fast_motion`): ρ_s·v with ρ_s = r_s + (∂z/∂y)ᵀg̃_s = r_s − Σ_t k_t (g̃_sᵀw_t) r_t,
    /// g̃_s the section's row on the fast body coordinates, w_t = K_f⁻¹g_t. So D_c = Σ c_s ρ_s ρ_sᵀ.
    /// Newton's matrix of the discrete gradient needs it: without it the step converged at h·ζω
    /// of the mesh mode per iteration (1.2 % at 1.5 kHz, 10 µs), three to four solves a step;
    /// with r_s for ρ_s it over-damped the iteration on the small helical pair (15 % more solves).
    fn slow_mesh_damper_acceleration(
        &self,
        qs: &QuasiStatic,
        p: &Prediction,
        w: &[DVector<f64>],
        slow_rows: DMatrix<f64>,
    ) -> Option<DMatrix<f64>> {
        let total: f64 = p.stiffness.iter().sum();
        if p.stiffness.is_empty() || self.mesh_damping_n_s_per_m <= 0.0 || total <= 0.0 {
            return None;
        }
        let n_s = p.slow_rows.len();
        let mut rho = slow_rows;
        let n_z0 = qs.fast.borrow()[0].len();
        let fast_bodies = [(0, qs.splits[0].fast_body_size()), (n_z0, qs.splits[1].fast_body_size())];
        if fast_bodies.iter().any(|&(_, n)| n > 0) {
            let on_bodies = |g: &DVector<f64>, w: &DVector<f64>| -> f64 {
                fast_bodies.iter().map(|&(o, n)| (o..o + n).map(|a| g[a] * w[a]).sum::<f64>()).sum()
            };
            let c = DMatrix::from_fn(n_s, n_s, |s, t| p.stiffness[t] * on_bodies(&p.fast_rows[s], &w[t]));
            let r = rho.clone();
            rho -= c * r;
        }
        let damped = DMatrix::from_fn(n_s, rho.ncols(), |s, j| {
            self.mesh_damping_n_s_per_m * p.stiffness[s] / total * rho[(s, j)]
        });
        let mut d = rho.transpose() * damped;
        self.slow_accelerations(qs, &mut d);
        d.iter().all(|x| x.is_finite()).then_some(d)
    }

    /// M⁻¹ on the rows of a force matrix of the slow coordinates: per gear θ by J, ξ by M_ξ.
    fn slow_accelerations(&self, qs: &QuasiStatic, a: &mut DMatrix<f64>) {
        let l = self.layout();
        for i in 0..2 {
            let sp = &qs.splits[i];
            let q = l.q(i);
            let n = l.n_q[i];
            a.row_mut(q).scale_mut(1.0 / sp.inertia_kgm2);
            if !sp.xi_mass_is_unit {
                let solved = &sp.xi_mass_inverse * a.rows(q + 1, n - 1);
                a.rows_mut(q + 1, n - 1).copy_from(&solved);
            }
        }
    }

    /// Keeps the solution's linearization for the next solve's start (`Prediction`).
    /// The section rows in the slow coordinates come from the caller, who made them for
    /// `damp_the_fast_motion` as well (once per solve).
    fn remember(
        &self,
        qs: &QuasiStatic,
        positions: &[f64],
        torques: [f64; 2],
        e: &mut Evaluation,
        slow_rows: Vec<Vec<f64>>,
    ) {
        let Some(tangent) = e.tangent.take() else { return };
        let sections = &e.outputs.contact.sections;
        *qs.prediction.borrow_mut() = Some(Prediction {
            positions: positions.to_vec(),
            torques,
            tangent,
            // The rows are not read after the solve (`shift_slow_forces` ran before).
            fast_rows: std::mem::take(&mut e.fast_rows),
            stiffness: sections.iter().map(|s| s.stiffness_n_per_m).collect(),
            slow_rows,
        });
    }

    /// The fast coordinates' first-order response to a move Δy of the slow positions from the
    /// last solve's equilibrium (the implicit function theorem, as `Prediction`): K·Δz =
    /// −Σ_s k_s·g_s·(r_s·Δy). Kept: z += Δz, and the prediction moves with it, so the next
    /// solve predicts from the moved point. Returns each gear's bore turn Δθ = Δφ − (Fᵀb/J)·Δz_Φ
    /// (the slow body coordinates do not turn the bore: Q ⟂ b), and each loaded section's
    /// approach change Δα_s = r_s·Δy + g_s·Δz. Without a solve in contact, the fast coordinates
    /// do not follow: Δθ = Δφ.
    pub(super) fn follow_slow_move(&self, qs: &QuasiStatic, dq: &[f64]) -> Result<([f64; 2], Vec<f64>), String> {
        let l = self.layout();
        let mut turn = [dq[l.q(0)], dq[l.q(1)]];
        let mut prediction = qs.prediction.borrow_mut();
        let Some(p) = prediction.as_mut() else { return Ok((turn, Vec::new())) };
        p.positions.iter_mut().zip(dq).for_each(|(y, d)| *y += d);
        if p.stiffness.is_empty() {
            return Ok((turn, Vec::new()));
        }
        let mut fast = qs.fast.borrow_mut();
        let n0 = fast[0].len();
        let mut force = DVector::zeros(n0 + fast[1].len());
        add_fast_load_of_slow_move(&p.fast_rows, &p.stiffness, &p.slow_rows, dq, &mut force);
        let dz = p.tangent.solve(&force, &p.fast_rows, &p.stiffness)?;
        let approach = (p.slow_rows.iter().zip(&p.fast_rows))
            .map(|(r, g)| r.iter().zip(dq).map(|(r, d)| r * d).sum::<f64>() + g.dot(&dz))
            .collect();
        for i in 0..2 {
            let offset = if i == 0 { 0 } else { n0 };
            fast[i].iter_mut().enumerate().for_each(|(k, z)| *z += dz[offset + k]);
            let bore_turn = &qs.splits[i].bore_turn;
            turn[i] -= (0..bore_turn.len()).map(|c| bore_turn[c] * dz[offset + c]).sum::<f64>();
        }
        Ok((turn, approach))
    }

    /// ẏ of the condensed pair and the outputs there; the fast coordinates found are kept for
    /// `unpack`. The input work is booked by the steppers on the bore's travel.
    pub(super) fn condensed_rhs(
        &self,
        qs: &QuasiStatic,
        y: &[f64],
        anchor: [i64; 2],
        torques: [f64; 2],
    ) -> Result<(Vec<f64>, PmorOutputs), String> {
        let l = self.layout();
        let e = self.solve_fast(qs, y, anchor, torques)?;
        let mut dy = vec![0.0; y.len()];
        let n_q = l.n_q[0] + l.n_q[1];
        dy[..n_q].copy_from_slice(&y[n_q..2 * n_q]);
        dy[n_q..2 * n_q].copy_from_slice(&e.acceleration);
        let n = y.len();
        dy[n - 1] = e.dissipation_w;
        Ok((dy, e.outputs))
    }

    /// M·x for the slow coordinates' constant mass (J on φ, Qᵀ(M_ΦΦ − bbᵀ/J)Q on ξ, per gear).
    pub(super) fn slow_mass_times(&self, qs: &QuasiStatic, x: &[f64], out: &mut [f64]) {
        let l = self.layout();
        for i in 0..2 {
            let sp = &qs.splits[i];
            let q = l.q(i);
            let n = l.n_q[i];
            out[q] = sp.inertia_kgm2 * x[q];
            // Column by column (gemv): the mass is stored column-major.
            let xi = nalgebra::DVectorView::from_slice(&x[q + 1..q + n], n - 1);
            let mut out_xi = nalgebra::DVectorViewMut::from_slice(&mut out[q + 1..q + n], n - 1);
            out_xi.gemv(1.0, &sp.xi_mass, &xi, 0.0);
        }
    }

    /// The outputs at a state as it stands (its fast coordinates not re-solved).
    pub(super) fn condensed_outputs(&self, qs: &QuasiStatic, s: &PmorState) -> Result<PmorOutputs, String> {
        let y = self.pack(s);
        let z = qs.fast.borrow().clone();
        Ok(self.evaluate(qs, &y, &z, s.anchor, s.torques_nm, false)?.outputs)
    }

    /// Slow coordinates of a state into y (mean-axis angle φ and ξ per gear), and its fast
    /// coordinates as Newton's next start.
    pub(super) fn condensed_pack(&self, qs: &QuasiStatic, s: &PmorState, y: &mut [f64]) {
        let l = self.layout();
        let mut fast = qs.fast.borrow_mut();
        // A state from outside: Newton starts from its own z, not from the last solve's tangent.
        *qs.prediction.borrow_mut() = None;
        for i in 0..2 {
            let g = &self.model.gears[i];
            let sp = &qs.splits[i];
            let n_k = g.modes();
            let eta_phi = DVector::from_column_slice(&s.eta[i][..n_k]);
            let eta_phi_dot = DVector::from_column_slice(&s.eta_dot[i][..n_k]);
            let (q, v) = (l.q(i), l.v(i));
            y[q] = s.theta[i] + sp.b.dot(&eta_phi) / sp.inertia_kgm2;
            y[v] = s.omega[i] + sp.b.dot(&eta_phi_dot) / sp.inertia_kgm2;
            y[q + 1..q + l.n_q[i]].copy_from_slice((sp.basis.transpose() * &eta_phi).as_slice());
            y[v + 1..v + l.n_q[i]].copy_from_slice((sp.basis.transpose() * &eta_phi_dot).as_slice());
            let z = &mut fast[i];
            let r = sp.fast_body_size();
            z[..r].copy_from_slice((sp.fast_basis.transpose() * &eta_phi).as_slice());
            z[r..].copy_from_slice(&s.eta[i][n_k..]);
        }
    }

    /// The state from y and the fast coordinates of the last solve: θ, η as the FE fields have
    /// them; ω and η̇ of the slow motion (η̇_Ψ = 0, and η̇_Φ without the hub direction's rate).
    pub(super) fn condensed_unpack(&self, qs: &QuasiStatic, y: &[f64], s: &mut PmorState) {
        let l = self.layout();
        let fast = qs.fast.borrow();
        for i in 0..2 {
            let n_k = self.model.gears[i].modes();
            let (eta, theta, velocity) = self.expand(qs, &l, y, i, &fast[i]);
            s.theta[i] = theta;
            s.eta[i].copy_from_slice(&eta);
            s.omega[i] = velocity[0];
            s.eta_dot[i][..n_k].copy_from_slice(&velocity[1..]);
            s.eta_dot[i][n_k..].fill(0.0);
        }
    }

    /// Moves the fast coordinates to their equilibrium under `torques` at the state's slow
    /// coordinates, booking the new torques' work τ_new·Δθ and, where they changed, the part of
    /// it the stored energy does not take as dissipated.
    /// Returns the right-hand side there (condensed), a time stepper's first.
    pub fn settle(&self, s: &mut PmorState, torques: [f64; 2]) -> Result<Option<(Vec<f64>, PmorOutputs)>, String> {
        self.settle_knowing(s, torques, None)
    }

    /// `settle` where the caller knows the elastic and contact energy at `s` (J; `outputs(s)`'s).
    pub fn settle_knowing(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        stored_j: Option<f64>,
    ) -> Result<Option<(Vec<f64>, PmorOutputs)>, String> {
        let Some(qs) = self.condensed() else {
            s.torques_nm = torques;
            return Ok(None);
        };
        let before = s.theta;
        let stored = |o: &PmorOutputs| o.elastic_j + o.contact_j;
        let stored_before = match (torques != s.torques_nm, stored_j) {
            (false, _) => None,
            (true, Some(u)) => Some(u),
            (true, None) => Some(stored(&self.condensed_outputs(qs, s)?)),
        };
        let y = self.pack(s);
        let first = self.condensed_rhs(qs, &y, s.anchor, torques)?;
        self.condensed_unpack(qs, &y, s);
        // The new torques do τ·Δθ on the bore's move. The fast coordinates, massless, relax at
        // once to the minimum of U − τ·θ, so U rises by no more than that work: the rest is
        // what a step load would set ringing in the fast modes, dissipated (≥ 0 by the minimum
        // principle; below the solve's noise it is taken as zero).
        let work: f64 = (0..2).map(|i| torques[i] * (s.theta[i] - before[i])).sum();
        s.input_work_j += work;
        if let Some(u) = stored_before {
            s.dissipated_j += (work - (stored(&first.1) - u)).max(0.0);
        }
        s.torques_nm = torques;
        Ok(Some(first))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Householder complement is orthonormal and orthogonal to b̂.
    #[test]
    fn the_slow_basis_is_the_orthonormal_complement_of_the_hub_direction() {
        for b in [[0.3, -0.8, 0.1, 0.5], [-0.9, 0.1, 0.0, 0.2]] {
            let b_hat = DVector::from_column_slice(&b).normalize();
            let q = complement(&b_hat);
            assert!((q.transpose() * &q - DMatrix::identity(3, 3)).norm() < 1e-14);
            assert!((q.transpose() * &b_hat).norm() < 1e-14);
        }
    }
}

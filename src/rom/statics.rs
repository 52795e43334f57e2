//! Static contact analysis of the reduced pair (paper Eq. 23; Eq. 18 for the baseline): gear 2
//! held at θ₂, torque T₁ on gear 1; unknowns r_b1·θ₁ and both gears' reduced coordinates.
//!
//! Every contact, whatever its law, is a scalar element: a penetration that is affine in the
//! unknowns, α = α₀ + s·(r_b1θ₁ − ref) + g₁·q₁ + g₂·q₂, a force P(α) ≥ 0, and the reduced loads
//! P·b₁, P·b₂ it puts on the gears. Equilibrium is
//!   T₁/r_b1 = Σ s·P,    K_i·q_i = Σ P·b_i   (i = 1, 2),
//! solved by Newton–Raphson with a backtracking line search. For PMOR-Hertz the elements are the
//! axial sections of the tooth pairs, P(α) the inverse of the Hertz load–approach relation (the
//! inner loop: a bracketed Newton per section) and b the Hertz pressure band integrated over the
//! flank; for the penalty baseline they are flank nodes against the mating flank (node-to-surface,
//! both passes) with P = k·max(α, 0).
//! The contact search is redone at the converged angle until the transmission error settles.

use super::reductor::ReducedGear;
use crate::contact::hertz::ApproachLaw;
use crate::contact::mesh_kinematics::{ContactKind, PairPlacement, SectionContact};
use crate::dynamics::iso6336;
use crate::gear::GearPair;
use nalgebra::{DMatrix, DVector};

/// How the flanks push on each other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactModel {
    /// Hertz line contact per axial section, approach referred to the depth h that the global
    /// attachment modes removed.
    Hertz { law: ApproachLaw, depth_m: f64 },
    /// Node-to-surface penalty, both passes; each node's stiffness is `factor` × the ISO 6336
    /// mesh stiffness c_γα of its axial share of the face (the paper: two orders of magnitude
    /// stiffer than the bodies), halved per pass.
    Penalty { factor: f64 },
}

/// One contact element's state at the solution.
#[derive(Debug, Clone, Copy)]
pub struct ElementResult {
    pub pair: i64,
    pub section: usize,
    pub kind: ContactKind,
    pub force_n: f64,
    pub penetration_m: f64,
    /// Hertz contact half-width (0 for penalty elements).
    pub half_width_m: f64,
    pub radius_m: [f64; 2],
    /// The force's moment arm on gear 1 over r_b1.
    pub arm_ratio: f64,
}

/// The outcome of one static analysis.
#[derive(Debug, Clone)]
pub struct StaticCase {
    pub theta_rad: [f64; 2],
    pub torque_nm: f64,
    /// Static transmission error r_b1θ₁ − r_b2θ₂ (m).
    pub ste_m: f64,
    /// Total normal contact force (N).
    pub mesh_force_n: f64,
    pub pairs_in_contact: usize,
    /// Elements carrying load.
    pub elements: Vec<ElementResult>,
    /// Reduced coordinates of each gear: the global contact shape is S = ψ·q.
    pub reduced: [Vec<f64>; 2],
    pub newton_iterations: usize,
}

impl StaticCase {
    /// Normal force carried by each tooth pair, by pair index.
    pub fn force_per_pair(&self) -> Vec<(i64, f64)> {
        let mut out: Vec<(i64, f64)> = Vec::new();
        for e in &self.elements {
            match out.iter_mut().find(|(j, _)| *j == e.pair) {
                Some(entry) => entry.1 += e.force_n,
                None => out.push((e.pair, e.force_n)),
            }
        }
        out.sort_by_key(|&(j, _)| j);
        out
    }
}

/// The reduced pair with its contact model.
pub struct StaticModel<'a> {
    pub placement: PairPlacement,
    pub gears: [&'a ReducedGear; 2],
    pub contact: ContactModel,
}

enum Law {
    Hertz { contact: crate::contact::hertz::LineContact, geometry: SectionContact },
    Penalty { stiffness_n_per_m: f64 },
}

struct Element {
    result: ElementResult,
    alpha0: f64,
    arm: f64,
    gap: [Vec<f64>; 2],
    load: [Vec<f64>; 2],
    law: Law,
}

impl Element {
    /// P and dP/dα at penetration α.
    fn force(&self, alpha: f64) -> Result<(f64, f64), String> {
        match &self.law {
            Law::Hertz { contact, .. } => {
                let p = contact.force(alpha)?;
                Ok((p, if p > 0.0 { 1.0 / contact.compliance(p) } else { 0.0 }))
            }
            Law::Penalty { stiffness_n_per_m: k } => Ok(if alpha > 0.0 { (k * alpha, *k) } else { (0.0, 0.0) }),
        }
    }
}

/// Relative residual at which Newton stops (torque balance over T₁/r_b1, the gears' balance
/// over the size of their contact loads).
const FORCE_TOLERANCE: f64 = 1e-9;
const MAX_NEWTON: usize = 100;

impl<'a> StaticModel<'a> {
    pub fn new(pair: &GearPair, gears: [&'a ReducedGear; 2], contact: ContactModel) -> Self {
        StaticModel { placement: PairPlacement::new(pair), gears, contact }
    }

    fn pair(&self) -> &GearPair {
        &self.placement.pair
    }

    fn sections(&self) -> usize {
        self.gears[0].flank.layer_z_m.len() - 1
    }

    /// The contact elements at shaft angles θ (rigid penetrations evaluated there; `te_ref` is
    /// the r_b1θ₁ − r_b2θ₂ they were evaluated at).
    fn elements(&self, theta: [f64; 2]) -> Vec<Element> {
        match self.contact {
            ContactModel::Hertz { law, depth_m } => self.hertz_elements(theta, law, depth_m),
            ContactModel::Penalty { factor } => self.penalty_elements(theta, factor),
        }
    }

    fn hertz_elements(&self, theta: [f64; 2], law: ApproachLaw, depth_m: f64) -> Vec<Element> {
        let z = &self.gears[0].flank.layer_z_m;
        let mut out = Vec::new();
        for j in self.placement.pairs_in_reach() {
            for s in 0..self.sections() {
                let z_mid = 0.5 * (z[s] + z[s + 1]);
                let Some(c) = self.placement.section_contact(theta, j, s, z_mid) else { continue };
                let (Some(s1), Some(s2)) = (
                    self.gears[0].flank.point_shares(c.teeth[0], c.radius_m[0], s),
                    self.gears[1].flank.point_shares(c.teeth[1], c.radius_m[1], s),
                ) else {
                    continue;
                };
                let gap = [
                    self.gears[0].projected_row(&s1, self.gears[0].flank.normal(&s1)),
                    self.gears[1].projected_row(&s2, self.gears[1].flank.normal(&s2)),
                ];
                let contact = c.line_contact(self.pair(), z[s + 1] - z[s], depth_m, law);
                out.push(Element {
                    result: ElementResult {
                        pair: j,
                        section: s,
                        kind: c.kind,
                        force_n: 0.0,
                        penetration_m: 0.0,
                        half_width_m: 0.0,
                        radius_m: c.radius_m,
                        arm_ratio: c.arm_ratio,
                    },
                    alpha0: c.rigid_penetration_m,
                    arm: c.arm_ratio,
                    load: [gap[0].iter().map(|v| -v).collect(), gap[1].iter().map(|v| -v).collect()],
                    gap,
                    law: Law::Hertz { contact, geometry: c },
                });
            }
        }
        out
    }

    /// The Hertz pressure band of a section at force P, as reduced loads.
    fn hertz_band_loads(&self, geometry: &SectionContact, half_width_m: f64) -> Option<[Vec<f64>; 2]> {
        let p = self.pair();
        let base = [p.gear1.base_radius_m, p.gear2.base_radius_m];
        let mut loads = [Vec::new(), Vec::new()];
        for i in 0..2 {
            let shares = self.gears[i].flank.band_shares(
                geometry.teeth[i],
                geometry.radius_m[i],
                half_width_m,
                base[i],
                geometry.section,
            )?;
            loads[i] = self.gears[i].inward_load_row(&shares);
        }
        Some(loads)
    }

    fn penalty_elements(&self, theta: [f64; 2], factor: f64) -> Vec<Element> {
        let p = self.pair();
        let place = &self.placement;
        let cos_bb = p.base_helix_angle_rad.cos();
        let layers = &self.gears[0].flank.layer_z_m;
        let dz = (layers[layers.len() - 1] - layers[0]) / (layers.len() - 1) as f64;
        let c_gamma = iso6336::to_newton_per_metre(iso6336::mesh_stiffness_c_gamma_alpha(p), 1.0);
        let gears = [&p.gear1, &p.gear2];
        let mut out = Vec::new();
        for j in place.pairs_in_reach() {
            let teeth = [j.rem_euclid(p.gear1.teeth as i64) as usize, j.rem_euclid(p.gear2.teeth as i64) as usize];
            // Pass `slave`: the slave gear's nodes against the master gear's flank.
            for slave in 0..2 {
                let master = 1 - slave;
                let grid = &self.gears[slave].flank;
                let Some(slot) = grid.teeth.iter().position(|&t| t == teeth[slave]) else { continue };
                let per_tooth = grid.row_radius_m.len() * layers.len();
                for k in slot * per_tooth..(slot + 1) * per_tooth {
                    let normal = grid.nodes[k].1;
                    let layer = k % layers.len();
                    let x = grid.node_xy[k];
                    let z = layers[layer];
                    let w = place.to_world(slave, theta[slave], x);
                    let own = place.to_own(master, theta[master], w);
                    let r = own[0].hypot(own[1]);
                    let g = gears[master];
                    if !(g.form_radius_m.max(g.base_radius_m)..=g.tip_radius_m).contains(&r) {
                        continue;
                    }
                    let alpha0 = -cos_bb * place.distance_from_flank(master, j, z, own);
                    if alpha0 < -0.2 * p.base_pitch_m {
                        continue;
                    }
                    let Some(master_shares) = self.gears[master].flank.layer_shares(teeth[master], r, layer) else {
                        continue;
                    };
                    let arm = if slave == 1 {
                        cos_bb
                    } else {
                        cos_bb * place.arm_on_gear1_of_gear2_normal(w, theta[1], j, z) / p.gear1.base_radius_m
                    };
                    let slave_shares = vec![(k, 1.0)];
                    let mut gap = [Vec::new(), Vec::new()];
                    let mut load = [Vec::new(), Vec::new()];
                    gap[slave] = self.gears[slave].projected_row(&slave_shares, normal);
                    load[slave] = self.gears[slave].inward_load_row(&slave_shares);
                    let n_master = self.gears[master].flank.normal(&master_shares);
                    gap[master] = self.gears[master].projected_row(&master_shares, n_master);
                    load[master] = self.gears[master].inward_load_row(&master_shares);
                    let share = if layer == 0 || layer == layers.len() - 1 { 0.5 } else { 1.0 };
                    out.push(Element {
                        result: ElementResult {
                            pair: j,
                            section: layer,
                            kind: ContactKind::Conjugate,
                            force_n: 0.0,
                            penetration_m: 0.0,
                            half_width_m: 0.0,
                            radius_m: if slave == 0 { [x[0].hypot(x[1]), r] } else { [r, x[0].hypot(x[1])] },
                            arm_ratio: arm,
                        },
                        alpha0,
                        arm,
                        gap,
                        load,
                        law: Law::Penalty { stiffness_n_per_m: 0.5 * factor * c_gamma * share * dz },
                    });
                }
            }
        }
        out
    }

    /// Static equilibrium at θ₂ under torque T₁ (N·m, driving).
    pub fn solve(&self, theta2: f64, torque_nm: f64) -> Result<StaticCase, String> {
        let p = self.pair();
        let (rb1, rb2) = (p.gear1.base_radius_m, p.gear2.base_radius_m);
        if !(torque_nm.is_finite() && torque_nm > 0.0) {
            return Err(format!("torque must be positive and finite, got {torque_nm} N·m"));
        }
        let target = torque_nm / rb1;
        let (n1, n2) = (self.gears[0].size(), self.gears[1].size());
        let n = 1 + n1 + n2;
        let mut te = 0.0;
        let mut y = DVector::<f64>::zeros(n);
        let mut iterations = 0;
        let mut last_te = f64::NAN;
        for _search in 0..5 {
            let theta = [(rb2 * theta2 + te) / rb1, theta2];
            let mut elements = self.elements(theta);
            if elements.is_empty() {
                return Err(format!("no tooth pair within reach at θ₂ = {theta2} rad"));
            }
            let te_ref = te;
            if iterations == 0 {
                te = rigid_guess(&elements, target)?;
                y[0] = te - te_ref;
            } else {
                y[0] = 0.0;
            }
            // Residual, its scale (the size of the contact loads) and, if asked, the Jacobian.
            type Evaluation = (DVector<f64>, f64, Option<DMatrix<f64>>);
            let evaluate = |y: &DVector<f64>, elements: &mut Vec<Element>, jac: bool| -> Result<Evaluation, String> {
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
                    let alpha = e.alpha0 + e.arm * y[0] + dot(&e.gap[0], q[0]) + dot(&e.gap[1], q[1]);
                    let (force, slope) = e.force(alpha)?;
                    e.result.force_n = force;
                    e.result.penetration_m = alpha;
                    if let Law::Hertz { contact, geometry } = &e.law {
                        if force > 0.0 {
                            let beta = contact.half_width(force);
                            e.result.half_width_m = beta;
                            if let Some(loads) = self.hertz_band_loads(geometry, beta) {
                                e.load = loads;
                            }
                        }
                    }
                    if force == 0.0 && slope == 0.0 {
                        continue;
                    }
                    r[0] -= force * e.arm;
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
                        let rows: Vec<(usize, f64)> = std::iter::once((0, e.arm))
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
            let mut converged = false;
            for _ in 0..MAX_NEWTON {
                iterations += 1;
                let (r, scale, j) = evaluate(&y, &mut elements, true)?;
                let current = merit(&r, scale);
                let j = j.expect("Jacobian requested");
                let step = j.clone().lu().solve(&(-&r)).ok_or("singular Jacobian in the static contact solve")?;
                let mut t = 1.0;
                let mut accepted = false;
                for _ in 0..40 {
                    let trial = &y + &step * t;
                    if let Ok((rt, st, _)) = evaluate(&trial, &mut elements, false) {
                        if merit(&rt, st) < current || t < 1e-6 {
                            y = trial;
                            accepted = true;
                            break;
                        }
                    }
                    t *= 0.5;
                }
                if !accepted {
                    return Err(format!("line search failed at θ₂ = {theta2} rad, T₁ = {torque_nm} N·m"));
                }
                let (r, scale, _) = evaluate(&y, &mut elements, false)?;
                let small_step = (step[0] * t).abs() <= 1e-9 * (te_ref + y[0]).abs().max(1e-9);
                if merit(&r, scale).sqrt() <= FORCE_TOLERANCE && small_step {
                    converged = true;
                    break;
                }
            }
            if !converged {
                return Err(format!(
                    "static contact did not converge in {MAX_NEWTON} Newton iterations at θ₂ = {theta2} rad, T₁ = {torque_nm} N·m"
                ));
            }
            te = te_ref + y[0];
            if (te - last_te).abs() <= 1e-6 * te.abs() {
                // The converged contact must lie in the law's range (not the Newton iterates).
                for e in &elements {
                    if let (Law::Hertz { contact, .. }, true) = (&e.law, e.result.force_n > 0.0) {
                        contact.check_half_width(e.result.force_n).map_err(|m| {
                            format!("at θ₂ = {theta2} rad, T₁ = {torque_nm} N·m, tooth pair {}: {m}", e.result.pair)
                        })?;
                    }
                }
                let loaded: Vec<ElementResult> =
                    elements.iter().map(|e| e.result).filter(|r| r.force_n > 0.0).collect();
                let mut pairs: Vec<i64> = loaded.iter().map(|e| e.pair).collect();
                pairs.dedup();
                pairs.sort();
                pairs.dedup();
                return Ok(StaticCase {
                    theta_rad: [(rb2 * theta2 + te) / rb1, theta2],
                    torque_nm,
                    ste_m: te,
                    mesh_force_n: loaded.iter().map(|e| e.force_n).sum(),
                    pairs_in_contact: pairs.len(),
                    elements: loaded,
                    reduced: [y.as_slice()[1..1 + n1].to_vec(), y.as_slice()[1 + n1..].to_vec()],
                    newton_iterations: iterations,
                });
            }
            last_te = te;
            // Keep q; re-linearize the contact search at the new angle.
        }
        Err(format!("the contact search did not settle at θ₂ = {theta2} rad, T₁ = {torque_nm} N·m"))
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b.iter()).map(|(x, y)| x * y).sum()
}

/// r_b1θ₁ − ref of the rigid gears (q = 0) that carries the torque: bisection on a monotone sum.
fn rigid_guess(elements: &[Element], target: f64) -> Result<f64, String> {
    let total = |te: f64| -> Result<f64, String> {
        let mut f = 0.0;
        for e in elements {
            f += e.force(e.alpha0 + e.arm * te)?.0 * e.arm;
        }
        Ok(f)
    };
    let (mut lo, mut hi) = (-1e-3, 1e-6);
    while total(hi).unwrap_or(f64::INFINITY) < target {
        lo = hi;
        hi *= 2.0;
        if hi > 1e-2 {
            return Err("no rigid position carries the torque".into());
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        match total(mid) {
            Ok(f) if f < target => lo = mid,
            _ => hi = mid,
        }
        if hi - lo < 1e-15 {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

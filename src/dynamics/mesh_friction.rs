//! Tooth friction (issue 42): on every loaded contact, a force f along the flanks' common
//! tangent against their sliding, and what it does to the two gears.
//!
//! Kinematics (`closed_forms::gear_loss`, checked there against rigid-body motion): a contact at
//! u (m from T₁ on the transverse line of action, T₁T₂ = L) lies on two involutes with radii of
//! curvature ρ₁ = u and ρ₂ = L − u; the flanks slide at v = ω₁ρ₁ − ω₂ρ₂ (each speed in its
//! gear's own mesh sense), zero at the pitch point C and of opposite signs on either side. The
//! sliding is transverse: both surfaces move in transverse planes, so a helical pair's friction
//! has no axial part and the same arms.
//!
//! The friction force f, signed as v, acts on gear 1's flank against its sliding and on gear 2's
//! with it. Along the tangent its arm about Oᵢ is ρᵢ, so the torques in each gear's mesh sense
//! are −f·ρ₁ on gear 1 and +f·ρ₂ on gear 2, and their power −f·ω₁ρ₁ + f·ω₂ρ₂ = −f·v ≤ 0 is what
//! the mesh loses. The coast flanks obey the same formulas: the pair mirrored about its centre
//! line turns a coast contact into a drive contact with every speed reversed, and f is odd in v.
//!
//! Through zero sliding (the pitch point; a pair at rest) Coulomb's law is regularized:
//! f = μF_n·v/√(v² + v_ε²) — smooth, odd, |f| < μF_n, f·v ≥ 0 at every instant, so the energy
//! balance's friction term D = ∫f·v dt never decreases. Within |v| ≲ v_ε the friction is a
//! viscous damper of μF_n/v_ε: a pair held at rest by friction creeps, at sliding speeds below
//! v_ε times the share of the breakaway torque its load imbalance takes. That damper is stiff
//! for an explicit integrator; v_ε is the larger of `MIN_SLIDING_REGULARIZATION_M_PER_S` and the
//! narrowest band the model's integrator stays stable in at its step
//! (`lumped::sliding_regularization_m_per_s`).

use serde::{Deserialize, Serialize};

/// The narrowest v_ε (m/s), the sliding speed below which friction is regularized: a tenth of
/// the sliding a module-3 pair at 10 rpm shows at its tips (≈ 10 mm/s), so that the loss of a
/// running pair is Coulomb's; at operating speed the flanks slide at metres per second.
pub const MIN_SLIDING_REGULARIZATION_M_PER_S: f64 = 1e-3;

/// v_ε for an integrator step h (m/s): the larger of `MIN_SLIDING_REGULARIZATION_M_PER_S` and the
/// band in which friction's viscous rate stays within reach. Within the band friction is a damper
/// of μF_n/v_ε on each contact's sliding ω₁ρ₁ − ω₂ρ₂; on the two gears its rate is at most
/// λ = (μF_n/v_ε)·`reach` with `reach` = max over the path of ρ₁²/J₁ + ρ₂²/J₂ (1/kg). v_ε is set
/// so that h·λ = `step_times_rate`: 2 for RK4 (stable to 2.78 on the real axis), 1 for the
/// discrete gradient, whose Newton leaves friction out of its matrix and so takes it by a
/// fixed-point iteration that contracts as h·λ/2.
pub fn regularization_for_step_m_per_s(
    coefficient: f64,
    normal_force_n: f64,
    reach_per_kg: f64,
    step_s: f64,
    step_times_rate: f64,
) -> f64 {
    (coefficient * normal_force_n * reach_per_kg * step_s / step_times_rate).max(MIN_SLIDING_REGULARIZATION_M_PER_S)
}

/// max over the path A…E of ρ₁²/J₁ + ρ₂²/J₂ (1/kg): convex in u, so at an end.
pub fn friction_reach_per_kg(loa_m: f64, path_m: [f64; 2], inertia_kgm2: [f64; 2]) -> f64 {
    let reach = |u: f64| u * u / inertia_kgm2[0] + (loa_m - u).powi(2) / inertia_kgm2[1];
    reach(path_m[0]).max(reach(path_m[1]))
}

/// v_ε for the pair's own geometry and a step h (m/s): `regularization_for_step_m_per_s` with F_n
/// the yield force (the largest the models answer for, `rating::yield_mesh_force_n`, over
/// cos β_b) on the gears' inertias J (kg·m²), at h·λ = `step_times_rate`.
pub fn regularization_for_pair_m_per_s(
    pair: &crate::gear::GearPair,
    coefficient: f64,
    inertia_kgm2: [f64; 2],
    step_s: f64,
    step_times_rate: f64,
) -> f64 {
    let reach = friction_reach_per_kg(pair.loa_length_m(), [pair.path_start_m, pair.path_end_m], inertia_kgm2);
    let normal = crate::closed_forms::rating::yield_mesh_force_n(pair) / pair.base_helix_angle_rad.cos();
    regularization_for_step_m_per_s(coefficient, normal, reach, step_s, step_times_rate)
}

/// The friction law: Coulomb's μ, regularized below v_ε.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingFriction {
    pub coefficient: f64,
    pub regularization_m_per_s: f64,
}

impl SlidingFriction {
    /// The regularized Coulomb friction force (N, signed as the sliding speed): μF_n·v/√(v² + v_ε²).
    pub fn force_n(&self, normal_force_n: f64, sliding_m_per_s: f64) -> f64 {
        let (v, e) = (sliding_m_per_s, self.regularization_m_per_s);
        self.coefficient * normal_force_n * v / (v * v + e * e).sqrt()
    }
}

/// What friction does at one contact, or summed over several.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactFriction {
    /// The friction torque on each gear (N·m, in its mesh sense): −f·ρ₁ and +f·ρ₂.
    pub torque_nm: [f64; 2],
    /// The power friction dissipates, f·v ≥ 0 (W).
    pub power_w: f64,
    /// The friction force f (N, signed as the sliding: positive where gear 1's flank runs ahead).
    pub force_n: f64,
}

impl ContactFriction {
    /// The friction of a contact at u (m from T₁) carrying the normal force F_n ≥ 0, with the
    /// gears at speeds ω (rad/s, each in its mesh sense), L = T₁T₂.
    pub fn at(law: SlidingFriction, loa_m: f64, u_m: f64, omega_rad_s: [f64; 2], normal_force_n: f64) -> Self {
        let (rho_1, rho_2) = (u_m, loa_m - u_m);
        let sliding = omega_rad_s[0] * rho_1 - omega_rad_s[1] * rho_2;
        let f = law.force_n(normal_force_n, sliding);
        ContactFriction { torque_nm: [-f * rho_1, f * rho_2], power_w: f * sliding, force_n: f }
    }

    fn add_scaled(&mut self, weight: f64, other: &ContactFriction) {
        self.torque_nm[0] += weight * other.torque_nm[0];
        self.torque_nm[1] += weight * other.torque_nm[1];
        self.power_w += weight * other.power_w;
        self.force_n += weight * other.force_n;
    }
}

/// Where a mesh force is carried along the line of action: per roll position ξᵢ = i·p_b/N (the
/// mesh law's rows) and force level F_k, the loaded contacts' shares of the force (Σ = 1) and
/// their points u (m from T₁), from the statics that made the law. Laid out by node i·K + k, each
/// node's contacts in `start[node]..start[node + 1]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactSpread {
    pub levels: usize,
    pub start: Vec<u32>,
    pub share: Vec<f64>,
    pub u_m: Vec<f64>,
}

/// Contacts closer than this along the line of action (over the base pitch) are kept as one,
/// at their force-weighted point: a spur pair's axial sections all touch at the same u.
const MERGE_OVER_BASE_PITCH: f64 = 1e-6;

impl ContactSpread {
    /// The spread from each node's contacts as (force N, u m), nodes laid out i·K + k. A node
    /// without load (the no-load level) takes the contacts of the next level up: the shares
    /// under the lightest load.
    pub fn from_contacts(levels: usize, base_pitch_m: f64, nodes: &[Vec<(f64, f64)>]) -> Result<Self, String> {
        if levels == 0 || nodes.is_empty() || nodes.len() % levels != 0 {
            return Err(format!("contact spread: {} nodes are not rows of {levels} levels", nodes.len()));
        }
        let mut out = ContactSpread { levels, start: vec![0], share: Vec::new(), u_m: Vec::new() };
        for n in 0..nodes.len() {
            let loaded = |c: &&Vec<(f64, f64)>| c.iter().any(|&(f, _)| f > 0.0);
            let k = n % levels;
            // The node itself, or the first loaded level above it in its row.
            let Some(contacts) = nodes[n..n - k + levels].iter().find(loaded) else {
                return Err(format!("contact spread: no loaded contact in row {} at or above level {k}", n / levels));
            };
            let mut sorted: Vec<(f64, f64)> = contacts.iter().copied().filter(|&(f, _)| f > 0.0).collect();
            sorted.sort_by(|a, b| a.1.total_cmp(&b.1));
            let total: f64 = sorted.iter().map(|c| c.0).sum();
            let mut merged: Vec<(f64, f64)> = Vec::new();
            for (f, u) in sorted {
                match merged.last_mut() {
                    Some((fm, um)) if (u - *um / *fm).abs() < MERGE_OVER_BASE_PITCH * base_pitch_m => {
                        *fm += f;
                        *um += f * u;
                    }
                    _ => merged.push((f, f * u)),
                }
            }
            for (f, fu) in merged {
                out.share.push(f / total);
                out.u_m.push(fu / f);
            }
            out.start.push(out.share.len() as u32);
        }
        out.check()?;
        Ok(out)
    }

    /// Checks a spread read from outside (a model file): its layout and finite values.
    pub fn check(&self) -> Result<(), String> {
        let layout_ok = self.levels > 0
            && self.start.len() >= 2
            && (self.start.len() - 1) % self.levels == 0
            && self.start[0] == 0
            && self.start.windows(2).all(|w| w[0] <= w[1])
            && *self.start.last().unwrap() as usize == self.share.len()
            && self.share.len() == self.u_m.len();
        let finite = self.share.iter().chain(&self.u_m).all(|x| x.is_finite());
        if !(layout_ok && finite) {
            return Err(
                "the contact spread (friction's contact points) is malformed or holds a non-finite value".into()
            );
        }
        Ok(())
    }

    /// Number of roll positions.
    pub fn rows(&self) -> usize {
        (self.start.len() - 1) / self.levels
    }

    fn node(&self, row: usize, level: usize) -> std::ops::Range<usize> {
        let n = row * self.levels + level;
        self.start[n] as usize..self.start[n + 1] as usize
    }

    /// The same spread with its rows taken from other rows (`row_of(i)`, the coast flank's mirror).
    pub fn with_rows_from(&self, row_of: impl Fn(usize) -> usize) -> ContactSpread {
        let mut out = ContactSpread { levels: self.levels, start: vec![0], share: Vec::new(), u_m: Vec::new() };
        for i in 0..self.rows() {
            for k in 0..self.levels {
                let r = self.node(row_of(i), k);
                out.share.extend_from_slice(&self.share[r.clone()]);
                out.u_m.extend_from_slice(&self.u_m[r]);
                out.start.push(out.share.len() as u32);
            }
        }
        out
    }

    /// The friction of the mesh force F_n ≥ 0 (along the flank normals) at roll ξ (m), on the
    /// rows and force levels of `table`, the flank's mesh law this spread was made beside.
    /// Between rows the contacts travel with the roll, `travel` (±1) m along the line of action
    /// per m of roll (+1 on the drive flank; −1 on the coast flank, whose contacts run from gear
    /// 1's tip to its root), and the two rows' frictions are blended linearly, as the law's
    /// deflections are; so are two force levels about the transverse force F_n·cos β_b.
    #[allow(clippy::too_many_arguments)]
    pub fn friction(
        &self,
        law: SlidingFriction,
        table: &super::mesh_law::MeshLaw,
        loa_m: f64,
        transverse_force_n: f64,
        normal_force_n: f64,
        roll_m: f64,
        travel: f64,
        omega_rad_s: [f64; 2],
    ) -> ContactFriction {
        let mut out = ContactFriction::default();
        if law.coefficient == 0.0 || normal_force_n <= 0.0 {
            return out;
        }
        let dx = table.base_pitch_m / table.rows() as f64;
        let (i, j, t) = table.row_position(roll_m);
        let (m, s) = table.level_position(transverse_force_n);
        let s = s.clamp(0.0, 1.0);
        for (row, row_weight, shift) in [(i, 1.0 - t, t * dx), (j, t, (t - 1.0) * dx)] {
            for (level, level_weight) in [(m, 1.0 - s), (m + 1, s)] {
                let weight = row_weight * level_weight;
                if weight == 0.0 {
                    continue;
                }
                for c in self.node(row, level) {
                    let u = self.u_m[c] + travel * shift;
                    let contact = ContactFriction::at(law, loa_m, u, omega_rad_s, self.share[c] * normal_force_n);
                    out.add_scaled(weight, &contact);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: SlidingFriction =
        SlidingFriction { coefficient: 0.05, regularization_m_per_s: MIN_SLIDING_REGULARIZATION_M_PER_S };

    /// The regularized law is odd, bounded by μF_n, dissipative at every speed, and Coulomb's
    /// well above v_ε (closed form: μF_n·sign v).
    #[test]
    fn regularized_friction_is_odd_bounded_dissipative_and_coulomb_beyond_the_band() {
        let (mu, f_n) = (0.05, 1000.0);
        let law = SlidingFriction { coefficient: mu, regularization_m_per_s: MIN_SLIDING_REGULARIZATION_M_PER_S };
        for v in [-3.0, -1e-2, -1e-4, 0.0, 1e-5, 1e-3, 0.2, 5.0] {
            let f = law.force_n(f_n, v);
            assert_eq!(f, -law.force_n(f_n, -v));
            assert!(f.abs() < mu * f_n && f * v >= 0.0);
            if v.abs() >= 1000.0 * law.regularization_m_per_s {
                assert!((f.abs() - mu * f_n).abs() < 1e-6 * mu * f_n, "{v}: {f}");
            }
        }
    }

    /// One contact's torques against the closed form: the sliding at the rigid speed ratio,
    /// arms ρ₁ = u and ρ₂ = L − u (evidence: `gear_loss::friction_arms_m`'s rigid-body check),
    /// signs changing at the pitch point, and the power f·v equal to minus the torques' power.
    #[test]
    fn a_contacts_torques_have_the_sliding_arms_and_change_sign_at_the_pitch_point() {
        let (loa, rb) = (0.04, [0.03, 0.05]);
        let pitch_point = loa * rb[0] / (rb[0] + rb[1]);
        let w1 = 100.0;
        let omega = [w1, w1 * rb[0] / rb[1]];
        for u in [0.005, pitch_point - 1e-3, pitch_point + 1e-3, 0.03] {
            let c = ContactFriction::at(LAW, loa, u, omega, 2000.0);
            // At the rigid speed ratio v = ω₁(r_b1 + r_b2)/r_b2·(u − C): zero at C.
            let sliding = w1 * (rb[0] + rb[1]) / rb[1] * (u - pitch_point);
            assert!((c.force_n - LAW.force_n(2000.0, sliding)).abs() < 1e-9 * 100.0, "{u}: {}", c.force_n);
            assert_eq!(c.force_n.signum(), (u - pitch_point).signum());
            assert!((c.torque_nm[0] + c.force_n * u).abs() < 1e-12);
            assert!((c.torque_nm[1] - c.force_n * (loa - u)).abs() < 1e-12);
            let torque_power = c.torque_nm[0] * omega[0] + c.torque_nm[1] * omega[1];
            assert!((c.power_w + torque_power).abs() < 1e-9 * c.power_w.abs() && c.power_w > 0.0);
        }
    }

    /// A spread's friction between rows: the contacts travel with the roll, so a single contact
    /// crosses the pitch point where its own position does, not at a row (evidence: the contact's
    /// position ξ-shifted by hand).
    #[test]
    fn contacts_travel_with_the_roll_between_rows() {
        let (pitch, loa, levels) = (0.01, 0.04, [0.0, 1000.0, 2000.0]);
        let rows = 10;
        // One contact per node at u = 0.02 + ξᵢ (so the same physical contact in every row).
        let nodes: Vec<Vec<(f64, f64)>> =
            (0..rows * 3).map(|n| vec![(1.0, 0.02 + pitch * (n / 3) as f64 / rows as f64)]).collect();
        let spread = ContactSpread::from_contacts(3, pitch, &nodes).unwrap();
        // The law whose rows and levels the spread was made beside (its deflections unread here).
        let table = crate::dynamics::mesh_law::MeshLaw::new(
            pitch,
            levels.to_vec(),
            (0..rows * 3).map(|n| 1e-6 * (n % 3) as f64).collect(),
        );
        let omega = [50.0, 50.0];
        for xi in [0.0013, 0.0047, 0.0081] {
            let got = spread.friction(LAW, &table, loa, 1500.0, 1500.0, xi, 1.0, omega);
            let want = ContactFriction::at(LAW, loa, 0.02 + xi, omega, 1500.0);
            assert!((got.torque_nm[0] - want.torque_nm[0]).abs() < 1e-9, "{xi}: {got:?} vs {want:?}");
            assert!((got.power_w - want.power_w).abs() < 1e-9 * want.power_w.abs());
        }
    }
}

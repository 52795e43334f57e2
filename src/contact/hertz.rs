//! Hertz line contact of two elastic cylinders: contact half-width, the load–approach relation
//! and its inverse.
//!
//! The approach of two bodies pressed together along a line is not defined by Hertz theory alone
//! (a 2-D half-space has no finite displacement): it must be referred to a depth inside each
//! body. We use Weber's form, per body i, referred to the depth hᵢ (design §4.3):
//!
//!   δᵢ = 2P(1−νᵢ²)/(π l Eᵢ) · [ln(2hᵢ/b) − νᵢ/(2(1−νᵢ))],   b = √(4PR/(π l E*)),
//!
//! with P the normal force, l the contact length, 1/R = 1/R₁ + 1/R₂ and
//! 1/E* = (1−ν₁²)/E₁ + (1−ν₂²)/E₂. Every logarithm has a dimensionless argument (2h/b), so the
//! value is the same in any unit system — unlike the paper's Eq. 20, whose logarithm carries a
//! length. The relation is monotone while b stays below about hᵢ (∂δ/∂P > 0); [`LineContact::force`]
//! refuses approaches beyond that range instead of returning a wrong branch.
//!
//! The paper's Eq. 20 (Harris & Kotzalas) is kept as [`ApproachLaw::PaperEq20`], made
//! consistent. As printed, α = 2P/(πl)·Σ(1−νᵢ²)/Eᵢ · ln[πl²/P·(1/R₁+1/R₂)·E*]; with
//! b² = 4PR/(πlE*) its logarithm's argument is 4l/b², a reciprocal length, so α depends on the
//! unit system. We multiply it by the one length the method defines, the reference depth h:
//! α = 2P/(πlE*)·ln(4lh/b²). Unlike Weber's form it depends on the slice length l, i.e. on the
//! axial mesh — which is what comparing the two shows.

use std::f64::consts::PI;

/// One body of the contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    pub youngs_modulus_pa: f64,
    pub poisson_ratio: f64,
    /// Radius of curvature of the surface at the contact line (normal plane).
    pub radius_of_curvature_m: f64,
    /// Depth inside the body to which the approach is referred.
    pub reference_depth_m: f64,
}

/// The load–approach relation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum ApproachLaw {
    /// Weber, per body, referred to each body's reference depth (dimensionally consistent).
    #[default]
    Weber,
    /// The paper's Eq. 20 with the reference depth as the length its logarithm lacks.
    PaperEq20,
}

/// The widest contact band Weber's approach is used for, as a fraction of the reference depth:
/// the law is the far-field form (b ≪ h) of the half-space solution, whose neglected terms are of
/// order (b/2h)² — under 2 % of the approach at b = h/4. The paper's heaviest loads stay below
/// h/10 at h = 3 mm; 100 × Table 4's torque reaches h/2 and is refused.
pub const MAX_HALF_WIDTH_OVER_DEPTH: f64 = 0.25;

/// The same fraction of the smaller radius of curvature: Hertz's solution takes each body as a
/// half-space near the band, which needs b ≪ ρ. It binds at tip edges (`Gear::tip_edge_radius_m`),
/// never on the flanks at the paper's loads (ρ ≥ 5 mm there, b ≤ 0.3 mm).
pub const MAX_HALF_WIDTH_OVER_RADIUS: f64 = 0.25;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineContact {
    pub length_m: f64,
    pub bodies: [Body; 2],
    pub law: ApproachLaw,
}

impl LineContact {
    /// E* with 1/E* = Σ (1−νᵢ²)/Eᵢ.
    pub fn effective_modulus(&self) -> f64 {
        1.0 / self.bodies.iter().map(|b| (1.0 - b.poisson_ratio.powi(2)) / b.youngs_modulus_pa).sum::<f64>()
    }

    /// R with 1/R = Σ 1/Rᵢ.
    pub fn effective_radius(&self) -> f64 {
        1.0 / self.bodies.iter().map(|b| 1.0 / b.radius_of_curvature_m).sum::<f64>()
    }

    /// Half-width b of the contact band under force P.
    pub fn half_width(&self, force_n: f64) -> f64 {
        (4.0 * force_n * self.effective_radius() / (PI * self.length_m * self.effective_modulus())).sqrt()
    }

    /// Peak Hertz pressure p₀ = 2P/(π b l).
    pub fn peak_pressure(&self, force_n: f64) -> f64 {
        2.0 * force_n / (PI * self.half_width(force_n) * self.length_m)
    }

    /// Both laws are Σᵢ aᵢ·P·(ln(kᵢ/b) − cᵢ) with aᵢ = 2(1−νᵢ²)/(πlEᵢ): per body (aᵢ, kᵢ, cᵢ).
    /// Weber: kᵢ = 2hᵢ, cᵢ = νᵢ/(2(1−νᵢ)). Eq. 20 made consistent: ln(4lh/b²) = 2 ln(2√(lh)/b),
    /// so kᵢ = 2√(l·hᵢ), cᵢ = 0, and each aᵢ counts twice.
    fn terms(&self) -> [(f64, f64, f64); 2] {
        self.bodies.map(|body| {
            let nu = body.poisson_ratio;
            let a = 2.0 * (1.0 - nu * nu) / (PI * self.length_m * body.youngs_modulus_pa);
            match self.law {
                ApproachLaw::Weber => (a, 2.0 * body.reference_depth_m, nu / (2.0 * (1.0 - nu))),
                ApproachLaw::PaperEq20 => (2.0 * a, 2.0 * (self.length_m * body.reference_depth_m).sqrt(), 0.0),
            }
        })
    }

    /// Approach δ(P) of the two reference depths (zero at zero force).
    pub fn hertz_approach(&self, force_n: f64) -> f64 {
        if force_n <= 0.0 {
            return 0.0;
        }
        let b = self.half_width(force_n);
        self.terms().iter().map(|&(a, k, c)| a * force_n * ((k / b).ln() - c)).sum()
    }

    /// The complementary energy W*(P) = ∫₀^P δ(p) dp. With δ = Σ aᵢ p (ln(kᵢ/b(p)) − cᵢ) and
    /// b ∝ √p: W* = Σ aᵢ P²/2 · (ln(kᵢ/b) − cᵢ + ¼). The contact potential at approach α is its
    /// Legendre transform W(α) = P·α − W*(P) with δ(P) = α (the dynamics' energy balance).
    pub fn complementary_energy(&self, force_n: f64) -> f64 {
        if force_n <= 0.0 {
            return 0.0;
        }
        let b = self.half_width(force_n);
        self.terms().iter().map(|&(a, k, c)| 0.5 * a * force_n * force_n * ((k / b).ln() - c + 0.25)).sum()
    }

    /// ∂W/∂R at fixed approach, R the effective radius: the potential's dependence on the
    /// geometry (Legendre: −∂W*/∂R at fixed P; b ∝ √R gives Σ aᵢ P²/(4R)).
    pub fn potential_radius_derivative(&self, force_n: f64) -> f64 {
        if force_n <= 0.0 {
            return 0.0;
        }
        self.terms().iter().map(|&(a, _, _)| a).sum::<f64>() * force_n * force_n / (4.0 * self.effective_radius())
    }

    /// dδ/dP (the contact compliance); infinite at P → 0 (the logarithmic singularity of line
    /// contact), and ≤ 0 beyond the range where the relation is valid.
    pub fn compliance(&self, force_n: f64) -> f64 {
        let b = self.half_width(force_n);
        self.terms().iter().map(|&(a, k, c)| a * ((k / b).ln() - c - 0.5)).sum()
    }

    /// `Err` naming the rule and the values when the band under P is wider than
    /// `MAX_HALF_WIDTH_OVER_DEPTH` × h, or than `MAX_HALF_WIDTH_OVER_RADIUS` × the smaller radius
    /// of curvature: a load beyond the validity of the approach law.
    pub fn check_half_width(&self, force_n: f64) -> Result<(), String> {
        let depth = self.bodies[0].reference_depth_m.min(self.bodies[1].reference_depth_m);
        let radius = self.bodies[0].radius_of_curvature_m.min(self.bodies[1].radius_of_curvature_m);
        let b = self.half_width(force_n);
        if b > MAX_HALF_WIDTH_OVER_RADIUS * radius {
            return Err(format!(
                "the Hertz half-width b = {:.4} mm under {force_n:.4e} N exceeds {MAX_HALF_WIDTH_OVER_RADIUS} × the smaller radius of curvature ρ = {:.4} mm: the load is beyond the validity of the contact law (it treats both bodies as half-spaces, b ≪ ρ); lower the load, or for a tip edge give its real edge radius",
                b * 1e3,
                radius * 1e3
            ));
        }
        if b > MAX_HALF_WIDTH_OVER_DEPTH * depth {
            return Err(format!(
                "the Hertz half-width b = {:.3} mm under {force_n:.4e} N exceeds {MAX_HALF_WIDTH_OVER_DEPTH} × the depth h = {:.3} mm: the load is beyond the validity of the contact law (it needs b ≪ h); lower the load or raise h",
                b * 1e3,
                depth * 1e3
            ));
        }
        Ok(())
    }

    /// The force P with δ(P) = δ: the inverse of [`LineContact::hertz_approach`], zero for δ ≤ 0,
    /// `Err` beyond the relation's valid range.
    ///
    /// With b = β√P the approach is δ = P·(C − ½S·ln P), S = Σ aᵢ, C = Σ aᵢ(ln(kᵢ/β) − cᵢ). In
    /// x = ln P the equation g(x) = x + ln(C − ½S·x) − ln δ = 0 is increasing and concave left of
    /// x* = 2C/S − 1 (where dδ/dP = 0, δ* = ½S·e^{x*}), so Newton's method started anywhere left
    /// of x* lands left of the root after one step and then rises to it monotonically and
    /// quadratically: four or five logarithms, against the bracketed Newton on P of
    /// [`series_force`] (the contact is inverted on every right-hand side of the dynamics).
    pub fn force(&self, approach_m: f64) -> Result<f64, String> {
        if approach_m <= 0.0 {
            return Ok(0.0);
        }
        let (c_sum, s_sum) = self.log_form();
        let x_star = 2.0 * c_sum / s_sum - 1.0;
        let approach_max = 0.5 * s_sum * x_star.exp();
        if !(approach_m < approach_max) {
            return Err(format!(
                "approach {approach_m:.3e} m exceeds the validity of the Hertz line-contact relation (max {approach_max:.3e} m at {:.3e} N)",
                x_star.exp()
            ));
        }
        let ln_approach = approach_m.ln();
        // Start at the linear law with the compliance at the valid range's end: x₀ < x*.
        let mut x = (ln_approach - (0.5 * s_sum).ln()).min(x_star - 1.0);
        // Converged when the step is at round-off: tiny, or no longer shrinking (near x* the
        // slope is small and the residual's round-off sets the floor).
        let mut last_step = f64::INFINITY;
        for _ in 0..60 {
            let arm = c_sum - 0.5 * s_sum * x;
            let g = x + arm.ln() - ln_approach;
            let slope = 1.0 - 0.5 * s_sum / arm;
            let dx = -g / slope;
            if dx.abs() <= 1e-15 * x.abs().max(1.0) || (dx.abs() >= last_step && dx.abs() < 1e-9) {
                return Ok((x + dx).exp());
            }
            x += dx;
            last_step = dx.abs();
        }
        Err(format!("the Hertz inverse did not converge at approach {approach_m:.3e} m"))
    }

    /// (C, S) of the law written as δ = P·(C − ½S·ln P): b = β√P, S = Σ aᵢ,
    /// C = Σ aᵢ(ln(kᵢ/β) − cᵢ).
    fn log_form(&self) -> (f64, f64) {
        let beta = self.half_width(1.0);
        let (mut c_sum, mut s_sum) = (0.0, 0.0);
        for (a, k, c) in self.terms() {
            c_sum += a * ((k / beta).ln() - c);
            s_sum += a;
        }
        (c_sum, s_sum)
    }

    /// The largest force for which δ(P) is still increasing: dδ/dP = C − ½S − ½S·ln P vanishes at
    /// ln P* = 2C/S − 1.
    pub fn max_valid_force(&self) -> f64 {
        let (c_sum, s_sum) = self.log_form();
        (2.0 * c_sum / s_sum - 1.0).exp()
    }
}

/// A contact in series with a linear spring (the rest of the structure): the total approach is
/// δ = P·c + δ_H(P). Returns P for a given δ by Newton's method inside a shrinking bracket;
/// zero for δ ≤ 0. `Err` if δ lies beyond the valid range of the Hertz relation, or if the
/// iteration reaches its cap without closing the bracket.
pub fn series_force(contact: &LineContact, structural_compliance: f64, approach_m: f64) -> Result<f64, String> {
    if approach_m <= 0.0 {
        return Ok(0.0);
    }
    let p_max = contact.max_valid_force();
    let total = |p: f64| p * structural_compliance + contact.hertz_approach(p);
    if total(p_max) < approach_m {
        return Err(format!(
            "approach {approach_m:.3e} m exceeds the validity of the Hertz line-contact relation (max {:.3e} m at {p_max:.3e} N)",
            total(p_max)
        ));
    }
    let (mut lo, mut hi) = (0.0, p_max);
    let mut p = approach_m / (structural_compliance + contact.compliance(p_max).max(0.0)).max(1e-300);
    p = p.clamp(lo, hi);
    for _ in 0..SERIES_FORCE_ITERATIONS {
        let residual = total(p) - approach_m;
        if residual > 0.0 {
            hi = p
        } else {
            lo = p
        }
        let slope = structural_compliance + contact.compliance(p.max(1e-300));
        let mut next = p - residual / slope;
        if !(next > lo && next < hi) || !next.is_finite() {
            next = 0.5 * (lo + hi);
        }
        if (next - p).abs() <= 1e-14 * p.max(1e-300) || hi - lo <= 1e-14 * hi {
            return Ok(next);
        }
        p = next;
    }
    Err(format!(
        "the series contact's force iteration hit its cap of {SERIES_FORCE_ITERATIONS} at approach {approach_m:.3e} m \
         (bracket [{lo:.6e}, {hi:.6e}] N not closed to 1e-14)"
    ))
}

/// The cap of `series_force`'s safeguarded Newton: bisection alone closes the bracket from the
/// valid range to 1e-14 in under 50 halvings, so reaching it means something is wrong.
pub const SERIES_FORCE_ITERATIONS: usize = 100;

#[cfg(test)]
mod tests {
    use super::*;

    fn steel_pair() -> LineContact {
        let body = |r| Body {
            youngs_modulus_pa: 2e11,
            poisson_ratio: 0.3,
            radius_of_curvature_m: r,
            reference_depth_m: 4.7e-3,
        };
        LineContact { length_m: 0.015, bodies: [body(0.0215), body(0.0318)], law: ApproachLaw::Weber }
    }

    /// The inverse against the forward law (round trip), and against the bracketed Newton of
    /// `series_force`, from light contact to 99 % of the valid range, both laws.
    #[test]
    fn force_inverts_the_approach_across_the_valid_range() {
        for law in [ApproachLaw::Weber, ApproachLaw::PaperEq20] {
            let c = LineContact { law, ..steel_pair() };
            let p_max = c.max_valid_force();
            for f in [1e-9, 1e-6, 1e-3, 0.1, 0.5, 0.9, 0.99] {
                let p = f * p_max;
                let delta = c.hertz_approach(p);
                let back = c.force(delta).unwrap();
                assert!(((back - p) / p).abs() < 1e-11, "{law:?} at {f}: {back} vs {p}");
                let bracketed = series_force(&c, 0.0, delta).unwrap();
                assert!(((back - bracketed) / p).abs() < 1e-11, "{law:?} at {f}");
            }
            assert!(c.force(1.001 * c.hertz_approach(p_max)).unwrap_err().contains("validity"));
            assert_eq!(c.force(0.0).unwrap(), 0.0);
        }
    }

    /// Quadrature: the closed-form complementary energy equals ∫₀^P δ(p) dp (Simpson on a
    /// √-graded grid, which resolves the p·ln p start), for both laws.
    #[test]
    fn complementary_energy_is_the_integral_of_the_approach() {
        for law in [ApproachLaw::Weber, ApproachLaw::PaperEq20] {
            let c = LineContact { law, ..steel_pair() };
            let p = 4000.0;
            let n = 4000;
            let mut integral = 0.0;
            for i in 0..n {
                let (s0, s1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
                let sm = 0.5 * (s0 + s1);
                // p = P s², dp = 2 P s ds
                let f = |s: f64| c.hertz_approach(p * s * s) * 2.0 * p * s;
                integral += (s1 - s0) / 6.0 * (f(s0) + 4.0 * f(sm) + f(s1));
            }
            let closed = c.complementary_energy(p);
            assert!(((closed - integral) / closed).abs() < 1e-9, "{law:?}: {closed} vs {integral}");
        }
    }

    /// Closed form: b = √(4PR/(πlE*)) and p₀ = 2P/(πbl) (Johnson, Contact Mechanics, Eq. 4.43).
    #[test]
    fn half_width_and_pressure_match_the_closed_form() {
        let c = steel_pair();
        let p = 3125.0;
        let r = 1.0 / (1.0 / 0.0215 + 1.0 / 0.0318);
        let e_star = 2e11 / (2.0 * (1.0 - 0.09));
        let b = (4.0 * p * r / (PI * 0.015 * e_star)).sqrt();
        assert!((c.half_width(p) - b).abs() < 1e-15);
        assert!((c.peak_pressure(p) - 2.0 * p / (PI * b * 0.015)).abs() < 1e-3);
    }

    /// Dimensional consistency: the same contact in mm–N–MPa units gives the same approach (in mm).
    #[test]
    fn approach_is_independent_of_the_unit_system() {
        let si = steel_pair();
        let mut mm = si;
        mm.length_m *= 1e3;
        for b in &mut mm.bodies {
            b.youngs_modulus_pa *= 1e-6; // N/mm²
            b.radius_of_curvature_m *= 1e3;
            b.reference_depth_m *= 1e3;
        }
        for law in [ApproachLaw::Weber, ApproachLaw::PaperEq20] {
            let (mut si, mut mm) = (si, mm);
            (si.law, mm.law) = (law, law);
            let (d_si, d_mm) = (si.hertz_approach(3125.0), mm.hertz_approach(3125.0));
            assert!((d_si * 1e3 - d_mm).abs() < 1e-12 * d_mm, "{law:?}: {d_si} m vs {d_mm} mm");
        }
    }

    /// The consistent Eq. 20 is the printed formula with its logarithm's argument times h:
    /// 2P/(πlE*)·ln(πl²/P·(1/R)·E*·h), evaluated here literally.
    #[test]
    fn paper_eq20_is_the_printed_formula_times_the_reference_depth() {
        let mut c = steel_pair();
        c.law = ApproachLaw::PaperEq20;
        let (p, l, h) = (3125.0, c.length_m, c.bodies[0].reference_depth_m);
        let (e_star, r) = (c.effective_modulus(), c.effective_radius());
        let printed = 2.0 * p / (PI * l * e_star) * (PI * l * l / p / r * e_star * h).ln();
        assert!((c.hertz_approach(p) - printed).abs() < 1e-12 * printed);
    }

    #[test]
    fn inverse_round_trips_and_compliance_is_the_derivative() {
        for law in [ApproachLaw::Weber, ApproachLaw::PaperEq20] {
            inverse_round_trips_for(LineContact { law, ..steel_pair() });
        }
    }

    fn inverse_round_trips_for(c: LineContact) {
        for p in [1.0, 100.0, 3125.0, 2e4] {
            let d = c.hertz_approach(p);
            let back = series_force(&c, 0.0, d).unwrap();
            assert!((back - p).abs() < 1e-9 * p, "{p} → {d} → {back}");
            let with_spring = series_force(&c, 5e-9, d + p * 5e-9).unwrap();
            assert!((with_spring - p).abs() < 1e-9 * p);
            let h = 1e-6 * p;
            let numeric = (c.hertz_approach(p + h) - c.hertz_approach(p - h)) / (2.0 * h);
            assert!((numeric - c.compliance(p)).abs() < 1e-6 * numeric);
        }
        assert_eq!(series_force(&c, 1e-9, -1e-6).unwrap(), 0.0);
        assert!(series_force(&c, 0.0, 1.0).is_err(), "1 m of approach is beyond any valid Hertz load");
        let p_star = c.max_valid_force();
        assert!(c.compliance(p_star).abs() < 1e-9 * c.compliance(1.0), "∂δ/∂P vanishes at P*");
    }
}

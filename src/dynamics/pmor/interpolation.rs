//! Interpolation of the global contact shapes in the gear's angle (Eqs. 15–16 and a C¹
//! alternative): Ψ(ϑ) = Σₐ wₐ(p)·S_{s−1+a}, a = 0…3, on the interval ϑ ∈ [ϑ_s, ϑ_{s+1}),
//! p = (ϑ − ϑ_s)/Δϑ. The weights and their first two p-derivatives are what the Lagrangian needs.

use super::model::Interpolation;

/// Weights of the four samples s−1 … s+2 and their derivatives d/dp, d²/dp².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weights {
    pub w: [f64; 4],
    pub dw: [f64; 4],
    pub ddw: [f64; 4],
}

impl Interpolation {
    pub fn weights(self, p: f64) -> Weights {
        match self {
            Interpolation::Linear => Weights { w: [0.0, 1.0 - p, p, 0.0], dw: [0.0, -1.0, 1.0, 0.0], ddw: [0.0; 4] },
            Interpolation::CatmullRom => {
                let (p2, p3) = (p * p, p * p * p);
                Weights {
                    w: [
                        0.5 * (-p3 + 2.0 * p2 - p),
                        0.5 * (3.0 * p3 - 5.0 * p2 + 2.0),
                        0.5 * (-3.0 * p3 + 4.0 * p2 + p),
                        0.5 * (p3 - p2),
                    ],
                    dw: [
                        0.5 * (-3.0 * p2 + 4.0 * p - 1.0),
                        0.5 * (9.0 * p2 - 10.0 * p),
                        0.5 * (-9.0 * p2 + 8.0 * p + 1.0),
                        0.5 * (3.0 * p2 - 2.0 * p),
                    ],
                    ddw: [
                        0.5 * (-6.0 * p + 4.0),
                        0.5 * (18.0 * p - 10.0),
                        0.5 * (-18.0 * p + 8.0),
                        0.5 * (6.0 * p - 2.0),
                    ],
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both schemes reproduce the samples, keep a constant field (weights sum to 1), and the
    /// cubic one is C¹: its slope at p = 1 of one interval equals that at p = 0 of the next.
    #[test]
    fn weights_interpolate_and_the_cubic_is_c1() {
        for scheme in [Interpolation::Linear, Interpolation::CatmullRom] {
            let at0 = scheme.weights(0.0);
            assert_eq!(at0.w[1], 1.0);
            for p in [0.0, 0.3, 0.77, 1.0] {
                let w = scheme.weights(p);
                assert!((w.w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
                assert!(w.dw.iter().sum::<f64>().abs() < 1e-15);
                // Finite-difference check of the derivatives.
                let h = 1e-6;
                let (a, b) = (scheme.weights(p + h), scheme.weights(p - h));
                for k in 0..4 {
                    assert!(((a.w[k] - b.w[k]) / (2.0 * h) - w.dw[k]).abs() < 1e-8);
                    assert!(((a.dw[k] - b.dw[k]) / (2.0 * h) - w.ddw[k]).abs() < 1e-7);
                }
            }
        }
        // Sample values f_{−1..2}: slope at the end of [0,1] vs at the start of [1,2].
        let f = [0.3, -1.0, 2.0, 0.5, 4.0];
        let cr = Interpolation::CatmullRom;
        let (end, start) = (cr.weights(1.0), cr.weights(0.0));
        let slope_end: f64 = (0..4).map(|k| end.dw[k] * f[k]).sum();
        let slope_start: f64 = (0..4).map(|k| start.dw[k] * f[k + 1]).sum();
        assert!((slope_end - slope_start).abs() < 1e-12);
    }
}

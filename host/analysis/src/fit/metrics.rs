//! Goodness of fit exactly as `models.md` §3 defines it (Spieringhs eq. 16,
//! 19, 20; Belcour eq. 8), over measured `f_m` and model `f_r` in the units
//! of the data.

use serde::Serialize;

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Metrics {
    pub rmse: f64,
    pub nrmse: f64,
    pub ncc: f64,
    pub l2: f64,
}

impl Metrics {
    /// The four figures as text, `RMSE` and `L2` in the data's units: four
    /// significant digits, NCC to five decimals.
    pub fn summary(&self) -> String {
        use crate::rounding::{figure, significant};
        format!(
            "RMSE {}  NRMSE {}  NCC {}  L2 {}",
            significant(self.rmse, 4),
            significant(self.nrmse, 4),
            figure(self.ncc, 5),
            significant(self.l2, 4)
        )
    }

    pub fn new(measured: &[f64], model: &[f64]) -> Metrics {
        let n = measured.len() as f64;
        let ssr: f64 = measured.iter().zip(model).map(|(m, r)| (m - r) * (m - r)).sum();
        let sad: f64 = measured.iter().zip(model).map(|(m, r)| (m - r).abs()).sum();
        let max = measured.iter().chain(model).copied().fold(f64::NEG_INFINITY, f64::max);
        let (mm, mr) = (measured.iter().sum::<f64>() / n, model.iter().sum::<f64>() / n);
        let (mut cov, mut vm, mut vr) = (0.0, 0.0, 0.0);
        for (m, r) in measured.iter().zip(model) {
            cov += (m - mm) * (r - mr);
            vm += (m - mm) * (m - mm);
            vr += (r - mr) * (r - mr);
        }
        Metrics {
            rmse: (ssr / n).sqrt(),
            nrmse: sad / (max * n),
            ncc: cov / (vm * vr).sqrt(),
            l2: ssr.sqrt(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn definitions_by_hand() {
        let m = [1.0, 2.0, 3.0, 4.0];
        let r = [1.5, 2.0, 2.0, 4.5];
        let x = Metrics::new(&m, &r);
        // Σ(m−r)² = 0.25 + 0 + 1 + 0.25 = 1.5
        assert!((x.rmse - (1.5f64 / 4.0).sqrt()).abs() < 1e-15);
        assert!((x.l2 - 1.5f64.sqrt()).abs() < 1e-15);
        // Σ|m−r| = 2, max over both = 4.5
        assert!((x.nrmse - 2.0 / (4.5 * 4.0)).abs() < 1e-15);
        // means 2.5, 2.5; cov = (−1.5)(−1) + (−0.5)(−0.5) + (0.5)(−0.5) + (1.5)(2) = 4.5;
        // var m = 5, var r = 1 + 0.25 + 0.25 + 4 = 5.5
        assert!((x.ncc - 4.5 / (5.0f64 * 5.5).sqrt()).abs() < 1e-15);
        assert_eq!(Metrics::new(&m, &m).ncc, 1.0);
    }
}

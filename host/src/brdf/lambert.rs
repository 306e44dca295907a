//! `lambert`: `kd/π`.

pub fn eval(kd: f64) -> f64 {
    kd / std::f64::consts::PI
}

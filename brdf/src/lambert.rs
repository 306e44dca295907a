//! `lambert`: `kd/π`.

use super::scalar::Scalar;
use std::f64::consts::PI;

pub fn eval<T: Scalar>(p: &[T]) -> T {
    p[0] / PI
}

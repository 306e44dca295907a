//! Numbers as a physicist writes them, for text and the report (JSON and CSV
//! keep every digit): a value with its uncertainty is rounded to it, ILAC
//! P14 style, the uncertainty to two significant digits and the value to the
//! same decimal place, `4.61 ± 0.07`, with a shared power of ten when the
//! number is far from one, `(4.61 ± 0.07)×10⁻³`. Rounding is to the nearest
//! digit, as P14 allows; a value that is not a number says so in words.

/// Plain decimals between 10⁻³ and 10⁵; a shared power of ten beyond.
const PLAIN: std::ops::Range<i32> = -3..5;

/// `value ± u` rounded to `u` (two significant digits of `u`). Without a
/// usable `u` (zero, negative or not finite), the value to four significant
/// digits alone.
pub fn with_uncertainty(value: f64, u: f64) -> String {
    if !value.is_finite() {
        return not_a_number(value);
    }
    if !(u.is_finite() && u > 0.0) {
        return significant(value, 4);
    }
    // The decimal place of u's second significant digit, found again once
    // rounded (0.0996 rounds to 0.10, one place up).
    let mut place = decade(u) - 1;
    if (u / pow10(place)).round() >= 100.0 {
        place += 1;
    }
    let top = decade(value.abs().max(u));
    if PLAIN.contains(&top) {
        let decimals = (-place).max(0) as usize;
        let (v, e) = (round_to(value, place), round_to(u, place));
        format!("{} ± {}", fixed(v, decimals), fixed(e, decimals))
    } else {
        let scale = pow10(top);
        let decimals = (top - place).max(0) as usize;
        let (v, e) = (round_to(value, place) / scale, round_to(u, place) / scale);
        format!("({} ± {})×10{}", fixed(v, decimals), fixed(e, decimals), superscript(top))
    }
}

/// `value` to `digits` significant digits, plain or with a power of ten as
/// [`with_uncertainty`] writes it.
pub fn significant(value: f64, digits: u32) -> String {
    if !value.is_finite() {
        return not_a_number(value);
    }
    if value == 0.0 {
        return "0".into();
    }
    let top = decade(value.abs());
    let place = top - digits as i32 + 1;
    let mut v = round_to(value, place);
    // Rounding may carry into a new decade (9.99996 → 10.00).
    let top = if decade(v.abs()) > top {
        v = round_to(value, place + 1);
        top + 1
    } else {
        top
    };
    let place = top - digits as i32 + 1;
    if PLAIN.contains(&top) {
        fixed(v, (-place).max(0) as usize)
    } else {
        format!("{}×10{}", fixed(v / pow10(top), (top - place).max(0) as usize), superscript(top))
    }
}

/// A correlation or other figure without physical unit, to `decimals`, or
/// "undefined" where it has no value (NCC of a constant model or data).
pub fn figure(value: f64, decimals: usize) -> String {
    if value.is_finite() {
        fixed(value, decimals)
    } else {
        "undefined".into()
    }
}

fn not_a_number(value: f64) -> String {
    match value {
        v if v == f64::INFINITY => "∞".into(),
        v if v == f64::NEG_INFINITY => "−∞".into(),
        _ => "undefined".into(),
    }
}

/// The power of ten of `x`'s leading digit, exact at powers of ten whatever
/// `log10`'s last bit.
fn decade(x: f64) -> i32 {
    let e = x.log10().floor() as i32;
    if pow10(e + 1) <= x {
        e + 1
    } else if pow10(e) > x {
        e - 1
    } else {
        e
    }
}

/// 10^e as the nearest double (10^n is exact up to n = 22; one division
/// rounds its inverse correctly, where `powi` with a negative power may not).
fn pow10(e: i32) -> f64 {
    if e < 0 {
        1.0 / 10f64.powi(-e)
    } else {
        10f64.powi(e)
    }
}

/// `x` rounded to a multiple of 10^place, computed so that the digits kept
/// are exact (dividing by 10^place for negative places, where it is exact).
fn round_to(x: f64, place: i32) -> f64 {
    if place < 0 {
        (x * pow10(-place)).round() / pow10(-place)
    } else {
        (x / pow10(place)).round() * pow10(place)
    }
}

/// Fixed decimals, with no "−0.00": a value that rounds to zero is zero.
fn fixed(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$}");
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// `ⁿ` of a power of ten.
pub(crate) fn superscript(e: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if e < 0 {
        s.push('⁻');
    }
    for c in e.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c as usize - '0' as usize]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_value_keeps_the_decimal_of_its_uncertainty() {
        assert_eq!(with_uncertainty(4.6109, 7.3e-2), "4.611 ± 0.073");
        assert_eq!(with_uncertainty(4.6109, 0.07), "4.611 ± 0.070");
        assert_eq!(with_uncertainty(12345.0, 230.0), "12350 ± 230");
        assert_eq!(with_uncertainty(0.15838, 0.0123), "0.158 ± 0.012");
        assert_eq!(with_uncertainty(-2.5, 1.26), "-2.5 ± 1.3");
    }

    #[test]
    fn an_uncertainty_rounding_up_a_decade_keeps_two_digits() {
        assert_eq!(with_uncertainty(1.23456, 0.0996), "1.23 ± 0.10");
    }

    #[test]
    fn far_from_one_the_pair_shares_a_power_of_ten() {
        assert_eq!(with_uncertainty(4.6109e-5, 7.3e-7), "(4.611 ± 0.073)×10⁻⁵");
        assert_eq!(with_uncertainty(3.2e7, 4.4e5), "(3.200 ± 0.044)×10⁷");
    }

    #[test]
    fn a_value_on_zero_is_zero_not_minus_zero() {
        assert_eq!(with_uncertainty(-1e-9, 4.9e-3), "0.0000 ± 0.0049");
        assert_eq!(figure(-0.0000001, 5), "0.00000");
        assert_eq!(significant(0.0, 3), "0");
        assert_eq!(significant(0.001, 2), "0.0010");
        assert_eq!(significant(1000.0, 2), "1000");
    }

    #[test]
    fn without_an_uncertainty_four_significant_digits() {
        assert_eq!(with_uncertainty(0.322_547, 0.0), "0.3225");
        assert_eq!(with_uncertainty(0.322_547, f64::NAN), "0.3225");
        assert_eq!(significant(9.99996, 4), "10.00");
        assert_eq!(significant(1.5e-9, 2), "1.5×10⁻⁹");
        assert_eq!(significant(-123456.0, 3), "-1.23×10⁵");
    }

    #[test]
    fn what_is_not_a_number_says_so() {
        assert_eq!(figure(f64::NAN, 5), "undefined");
        assert_eq!(with_uncertainty(f64::NAN, 1.0), "undefined");
        assert_eq!(significant(f64::INFINITY, 3), "∞");
    }
}

//! Decimal numbers of text logs, read faster than `str::parse::<f64>` for
//! the plain form loggers write (`-0.644092377`) and to the same bit:
//! Clinger's fast path, where the digits as an integer `m <= 2^53` and the
//! count `e <= 22` after the point make `m / 10^e` one correctly rounded
//! division of two exact doubles, i.e. the correctly rounded value that
//! `parse` gives. Every other text (exponents, more digits, `inf`, ...)
//! goes to `parse`.

/// The powers of ten that doubles hold exactly.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `s` as a double exactly as `str::parse::<f64>` reads it (`None` where
/// it fails, or where `s` is not UTF-8). No trimming.
#[inline]
pub fn parse_f64(s: &[u8]) -> Option<f64> {
    fast(s).or_else(|| std::str::from_utf8(s).ok()?.parse().ok())
}

/// `[+-]digits[.digits]` (either part may be empty, not both) within the
/// fast path's bounds, else `None`.
#[inline]
fn fast(s: &[u8]) -> Option<f64> {
    parse_prefix(s)
        .filter(|&(_, n)| n == s.len())
        .map(|(x, _)| x)
}

/// The plain number at the start of `s` (`[+-]digits[.digits]`, up to the
/// first byte that cannot go on: not a digit, a second point or a 20th
/// digit) and its length in bytes, where the fast path reads it (so that
/// when it is all of a text, the value is [`parse_f64`]'s); else `None`.
/// For parsers that split fields as they go.
#[inline]
pub fn parse_prefix(s: &[u8]) -> Option<(f64, usize)> {
    let (neg, start) = match s.first()? {
        b'-' => (true, 1),
        b'+' => (false, 1),
        _ => (false, 0),
    };
    let (mut m, mut digits, mut point) = (0u64, 0u32, None);
    let mut i = start;
    while let Some(&b) = s.get(i) {
        let d = b.wrapping_sub(b'0');
        if d < 10 && digits < 19 {
            m = m * 10 + u64::from(d);
            digits += 1;
        } else if b == b'.' && point.is_none() {
            point = Some(i);
        } else {
            break;
        }
        i += 1;
    }
    let e = point.map_or(0, |p| i - p - 1);
    if digits == 0 || m > 1 << 53 || e >= POW10.len() {
        return None;
    }
    let x = m as f64 / POW10[e];
    Some((if neg { -x } else { x }, i))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn same(s: &str) {
        let want = s.parse::<f64>().ok();
        let got = parse_f64(s.as_bytes());
        assert_eq!(
            got.map(f64::to_bits),
            want.map(f64::to_bits),
            "'{s}': {got:?} vs {want:?}"
        );
        // A prefix before a comma is all of the text exactly when the fast
        // path reads the text, with its value.
        let field = format!("{s},9");
        let prefix = parse_prefix(field.as_bytes()).filter(|&(_, n)| n == s.len());
        assert_eq!(
            prefix.map(|(x, _)| x.to_bits()),
            fast(s.as_bytes()).map(f64::to_bits),
            "'{s}'"
        );
        if let Some((x, _)) = prefix {
            assert_eq!(Some(x.to_bits()), want.map(f64::to_bits), "'{s}'");
        }
    }

    #[test]
    fn equals_std_parse_to_the_bit() {
        for s in [
            "0",
            "-0",
            "+0",
            "-0.0",
            "1.",
            ".5",
            "-.5",
            ".",
            "-",
            "+",
            "",
            "1..2",
            "1.2.3",
            "0.1",
            "0.3",
            "-0.644092377",
            "9007199254740993",
            "9007199254740992.5",
            "1234567890123456789",
            "12345678901234567890",
            "0.0000000000000000000001",
            "0.00000000000000000000001",
            "1e5",
            "inf",
            "NaN",
            " 1",
            "1 ",
            "1,5",
            "٣",
            "179769313486231570000000000000000000000000000000000000000.0",
        ] {
            same(s);
        }
        // Random plain decimals (the fast path and its edges) and random
        // strings over the characters numbers are made of.
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for _ in 0..200_000 {
            let int: String = (0..rng.gen_range(0..12))
                .map(|_| char::from(b'0' + rng.gen_range(0..10)))
                .collect();
            let frac: String = (0..rng.gen_range(0..24))
                .map(|_| char::from(b'0' + rng.gen_range(0..10)))
                .collect();
            let sign = ["", "-", "+"][rng.gen_range(0..3)];
            same(&format!("{sign}{int}.{frac}"));
            same(&format!("{sign}{int}{frac}"));
            let junk: String = (0..rng.gen_range(0..8))
                .map(|_| b"0123456789.-+eE"[rng.gen_range(0..15)] as char)
                .collect();
            same(&junk);
        }
        // Doubles written shortest (ryu) and with 9 and 17 digits.
        for _ in 0..100_000 {
            let x: f64 = rng.gen_range(-10.0..10.0) * 10f64.powi(rng.gen_range(-8..8));
            same(&x.to_string());
            same(&format!("{x:.9}"));
            same(&format!("{x:.17}"));
        }
    }
}

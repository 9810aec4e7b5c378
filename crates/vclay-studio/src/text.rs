//! Text for the log: numbers rounded for reading.
//!
//! The session layer's messages print coordinates with every digit of an `f64` (a rope's
//! cursor at `[0.5123456789012345, ...]`); [`round_numbers`] rounds such numbers where the
//! studio shows them (its log and status line), leaving the session's own log untouched.

/// Fraction digits a number must have to be rounded: shorter ones were written that way on
/// purpose (`t = 0.0500`).
pub const LONG_FRACTION: usize = 5;
/// Decimals kept of a rounded number.
pub const DECIMALS: usize = 3;

/// `text` with every number of at least [`LONG_FRACTION`] fraction digits rounded to
/// [`DECIMALS`] decimals (trailing zeros dropped; numbers below `10^-DECIMALS` in magnitude
/// in scientific notation with as many significant decimals). Digits inside words, versions
/// and paths (after a letter, `_`, `.` or another digit) are left as they are.
pub fn round_numbers(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        let free = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || matches!(b[i - 1], b'_' | b'.'));
        if starts && free {
            let (end, fraction) = number_end(b, i);
            let token = &text[i..end];
            let followed = b
                .get(end)
                .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_');
            match token.parse::<f64>() {
                Ok(x) if fraction >= LONG_FRACTION && !followed => out.push_str(&round(x)),
                _ => out.push_str(token),
            }
            i = end;
        } else {
            // Copy one character (UTF-8 safe: continuation bytes are never digits or '-').
            let len = text[i..].chars().next().map_or(1, char::len_utf8);
            out.push_str(&text[i..i + len]);
            i += len;
        }
    }
    out
}

/// The end of the number starting at `i` and its count of fraction digits.
fn number_end(b: &[u8], mut i: usize) -> (usize, usize) {
    if b[i] == b'-' {
        i += 1;
    }
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    let mut fraction = 0;
    if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
        i += 1;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
            fraction += 1;
        }
    }
    // An exponent: e, an optional sign, digits.
    if i < b.len() && matches!(b[i], b'e' | b'E') {
        let mut j = i + 1;
        if j < b.len() && matches!(b[j], b'+' | b'-') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            i = j;
        }
    }
    (i, fraction)
}

fn round(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if x.abs() < 10f64.powi(-(DECIMALS as i32)) {
        return format!("{x:.DECIMALS$e}");
    }
    let s = format!("{x:.DECIMALS$}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

#[cfg(test)]
mod tests {
    use super::round_numbers;

    #[test]
    fn long_coordinates_are_rounded() {
        assert_eq!(
            round_numbers(
                "rope `studio-rope` cursor at [0.5123456789012345, -1.2000000000000002, 3.0]"
            ),
            "rope `studio-rope` cursor at [0.512, -1.2, 3.0]"
        );
        assert_eq!(
            round_numbers("moved control point 12 to [1.0000000001, 2.5e-7, 0.00012345678]"),
            "moved control point 12 to [1, 2.5e-7, 1.235e-4]"
        );
        assert_eq!(round_numbers("x 1.23456789e-12 y"), "x 1.235e-12 y");
    }

    #[test]
    fn short_numbers_names_and_paths_stay() {
        for s in [
            "rope `studio-rope` attached to data point 911",
            "t = 0.0500: gravity on",
            "saved /tmp/run.1234567/cube2.session",
            "vclay-studio v0.123456",
            "undone: material of 3 cell(s)",
            "ünïcode ok 0.25",
        ] {
            assert_eq!(round_numbers(s), s);
        }
    }
}

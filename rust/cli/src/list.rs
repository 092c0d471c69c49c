//! Parsing of comma-separated number lists given on the command line.

use sixaxis_core::Error;

/// Parse exactly `N` comma-separated finite numbers; the error names the flag and the value.
pub fn parse_fixed<const N: usize>(flag: &str, text: &str) -> Result<[f64; N], Error> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(Error::argument(
            flag,
            text,
            format!("expected {N} comma-separated numbers, got {}", parts.len()),
        ));
    }
    let mut out = [0.0; N];
    for (slot, part) in out.iter_mut().zip(&parts) {
        let v: f64 = part
            .parse()
            .map_err(|_| Error::argument(flag, text, format!("`{part}` is not a number")))?;
        if !v.is_finite() {
            return Err(Error::argument(
                flag,
                text,
                format!("`{part}` is not finite"),
            ));
        }
        *slot = v;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_negative_numbers() {
        assert_eq!(
            parse_fixed::<3>("--x", "-1, 2.5,-3").unwrap(),
            [-1.0, 2.5, -3.0]
        );
    }

    #[test]
    fn wrong_count_and_garbage_name_the_flag() {
        let e = parse_fixed::<3>("--position-mm", "1,2")
            .unwrap_err()
            .to_string();
        assert!(e.contains("--position-mm") && e.contains("1,2"), "{e}");
        let e = parse_fixed::<2>("--x", "1,abc").unwrap_err().to_string();
        assert!(e.contains("abc"), "{e}");
        assert!(parse_fixed::<1>("--x", "nan").is_err());
    }
}

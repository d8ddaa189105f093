//! Frame number tokens in file name patterns (per-frame OBJ sequences).

/// Substitutes the frame number for the one frame token in `pattern`: printf's `%d` / `%0Nd`,
/// Houdini's `$F` / `$FN` (zero-padded to N digits), or a run of N `#` (zero-padded to N).
pub(in crate::scene) fn format_frame(pattern: &str, n: i64) -> Result<String, String> {
    let bad =
        || format!("expected one frame number token, %04d, $F4 or #### (e.g. \"body_%04d.obj\"), in \"{pattern}\"");
    let tokens = [pattern.find('%'), pattern.find("$F"), pattern.find('#')];
    let (start, len, width, zero) = match tokens {
        [Some(start), None, None] => {
            let rest = &pattern[start + 1..];
            let digits = rest.find(|c: char| !c.is_ascii_digit()).ok_or_else(bad)?;
            if !rest[digits..].starts_with('d') {
                return Err(bad());
            }
            let width: usize = if digits == 0 { 0 } else { rest[..digits].parse().map_err(|_| bad())? };
            (start, digits + 2, width, rest.starts_with('0'))
        }
        [None, Some(start), None] => {
            let rest = &pattern[start + 2..];
            let digits = rest.find(|c: char| !c.is_ascii_digit()).unwrap_or(rest.len());
            let width: usize = if digits == 0 { 0 } else { rest[..digits].parse().map_err(|_| bad())? };
            (start, digits + 2, width, true)
        }
        [None, None, Some(start)] => {
            let hashes = pattern[start..].find(|c: char| c != '#').unwrap_or(pattern.len() - start);
            (start, hashes, hashes, true)
        }
        _ => return Err(bad()),
    };
    let tail = &pattern[start + len..];
    if tail.contains(['%', '#']) || tail.contains("$F") || width > 20 {
        return Err(bad());
    }
    let number = if zero { format!("{n:0width$}") } else { format!("{n:width$}") };
    Ok(format!("{}{number}{tail}", &pattern[..start]))
}

#[cfg(test)]
mod tests {
    use super::format_frame;

    #[test]
    fn frame_tokens_of_printf_houdini_and_hashes() {
        for pattern in ["body_%04d.obj", "body_$F4.obj", "body_####.obj"] {
            assert_eq!(format_frame(pattern, 7).unwrap(), "body_0007.obj", "{pattern}");
            assert_eq!(format_frame(pattern, 12345).unwrap(), "body_12345.obj", "{pattern}");
        }
        assert_eq!(format_frame("b%d.obj", 7).unwrap(), "b7.obj");
        assert_eq!(format_frame("b$F.obj", 7).unwrap(), "b7.obj");
        assert_eq!(format_frame("b#.obj", 7).unwrap(), "b7.obj");
        assert_eq!(format_frame("b%3d.obj", 7).unwrap(), "b  7.obj");
        for bad in ["body.obj", "b%04d_%d.obj", "b$F4_####.obj", "b%s.obj", "b##_#.obj", "b%04.obj"] {
            assert!(format_frame(bad, 1).is_err(), "{bad}");
        }
    }
}

//! One escaping of wire bytes for people, shared by `gcl explain`, traces, transcripts and
//! mismatch reports: printable ASCII stays, `\n` `\r` `\t` `\\` are escaped by letter, every
//! other byte is `\xHH`. [`unescape`] inverts it exactly.

/// Escapes bytes so that every byte is visible and the text is one line.
pub fn escape(bytes: &[u8]) -> String {
    escape_also(bytes, &[])
}

/// [`escape`], with every byte of `also` written as `\xHH` too: for a format where some
/// printable bytes delimit text (transcript strings: `"` and `{`). [`unescape`] inverts it.
pub fn escape_also(bytes: &[u8], also: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len());
    for &b in bytes {
        match b {
            _ if also.contains(&b) => s.push_str(&format!("\\x{b:02X}")),
            b'\n' => s.push_str("\\n"),
            b'\r' => s.push_str("\\r"),
            b'\t' => s.push_str("\\t"),
            b'\\' => s.push_str("\\\\"),
            0x20..=0x7e => s.push(b as char),
            _ => s.push_str(&format!("\\x{b:02X}")),
        }
    }
    s
}

/// Why escaped text does not decode.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum UnescapeError {
    /// A backslash followed by something other than `n r t \ xHH`.
    #[error("bad escape at column {0}")]
    BadEscape(usize),
    /// A character outside printable ASCII.
    #[error("unescaped non-printable character at column {0}")]
    Unprintable(usize),
}

/// Decodes [`escape`]d text.
pub fn unescape(text: &str) -> Result<Vec<u8>, UnescapeError> {
    let mut out = Vec::with_capacity(text.len());
    unescape_into(text, &mut out)?;
    Ok(out)
}

/// Decodes [`escape`]d text onto the end of `out` (what a parser reading many strings uses,
/// to reuse one buffer). On an error, `out` holds the bytes decoded before it.
pub fn unescape_into(text: &str, out: &mut Vec<u8>) -> Result<(), UnescapeError> {
    let b = text.as_bytes();
    let mut i = 0;
    while let Some(&c) = b.get(i) {
        match c {
            b'\\' => {
                let next = b.get(i + 1).copied();
                match next {
                    Some(b'n') => out.push(b'\n'),
                    Some(b'r') => out.push(b'\r'),
                    Some(b't') => out.push(b'\t'),
                    Some(b'\\') => out.push(b'\\'),
                    Some(b'x') => {
                        // Two hex digits exactly (`from_str_radix` alone would take `+F`).
                        let hex = text
                            .get(i + 2..i + 4)
                            .filter(|h| h.bytes().all(|d| d.is_ascii_hexdigit()))
                            .ok_or(UnescapeError::BadEscape(i))?;
                        let v = u8::from_str_radix(hex, 16).map_err(|_| UnescapeError::BadEscape(i))?;
                        out.push(v);
                        i += 2;
                    }
                    _ => return Err(UnescapeError::BadEscape(i)),
                }
                i += 2;
            }
            0x20..=0x7e => {
                out.push(c);
                i += 1;
            }
            _ => return Err(UnescapeError::Unprintable(i)),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_every_byte() {
        let all: Vec<u8> = (0..=255).collect();
        assert_eq!(unescape(&escape(&all)).unwrap(), all);
        assert_eq!(escape(b"HI\n\r=> \x03"), "HI\\n\\r=> \\x03");
        assert!(unescape("\\q").is_err());
        assert!(unescape("\\x4").is_err());
        assert!(unescape("\\x+F").is_err());
        assert_eq!(escape_also(b"a\"{\n", b"\"{"), "a\\x22\\x7B\\n");
    }
}

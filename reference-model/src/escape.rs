//! One escaping of wire bytes for people, shared by `gcl explain`, traces, transcripts and
//! mismatch reports: printable ASCII stays, `\n` `\r` `\t` `\\` are escaped by letter, every
//! other byte is `\xHH`. [`unescape`] inverts it exactly. [`printable`] does the same for
//! text that is already a string (a message quoting a host's command word, a signature, a
//! field of a file) before it reaches a terminal or an XML file.

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

/// Text with every control character written out, so that what a hand, a host or a file
/// put in it is shown, never obeyed: a terminal meets no escape sequence (`ESC]0;` retitling
/// the window, `ESC[2J` clearing it), no carriage return overwriting the line, and an XML
/// 1.0 file no character it forbids, and no bidirectional control reorders what a person
/// reads (U+202E, the right-to-left override, shows `exe.txt` for `txt.exe`). Newline and tab
/// stay (multi-line text keeps its lines); `\r` is written `\r`, the other C0 controls and DEL
/// `\xHH` as [`escape`] writes those bytes, the C1 controls, the bidirectional controls and
/// the non-characters U+FFFE and U+FFFF `\u{HHHH}`. A backslash stays as it is: text already
/// escaped (`"A\x00"`) is not escaped twice, so this is for people, not to be inverted. Text
/// without such characters is returned as it is, unallocated.
pub fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    let shown = |c: char| {
        matches!(c, '\n' | '\t') || !(c.is_control() || matches!(c, '\u{FFFE}' | '\u{FFFF}') || bidi_control(c))
    };
    if text.chars().all(shown) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut s = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            _ if shown(c) => s.push(c),
            '\r' => s.push_str("\\r"),
            '\0'..='\x7f' => s.push_str(&format!("\\x{:02X}", c as u32)),
            _ => s.push_str(&format!("\\u{{{:04X}}}", c as u32)),
        }
    }
    std::borrow::Cow::Owned(s)
}

/// Whether `c` is one of Unicode's bidirectional controls (the marks, embeddings, overrides
/// and isolates), which change the order in which the text around them is shown.
pub fn bidi_control(c: char) -> bool {
    matches!(c, '\u{061C}' | '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
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

    #[test]
    fn printable_text_has_no_control_character_but_newline_and_tab() {
        assert_eq!(printable("A\0\x1b[2J\r\x1b]0;t\x07"), "A\\x00\\x1B[2J\\r\\x1B]0;t\\x07");
        assert_eq!(printable("a\tb\nc \\x00 \u{e9}"), "a\tb\nc \\x00 \u{e9}");
        assert!(matches!(printable("plain"), std::borrow::Cow::Borrowed(_)));
        assert_eq!(printable("\u{9b}2J\u{7f}\u{fffe}\u{ffff}"), "\\u{009B}2J\\x7F\\u{FFFE}\\u{FFFF}");
        let every: String = (0..=0x10FFFFu32).filter_map(char::from_u32).collect();
        assert!(printable(&every).chars().all(|c| matches!(c, '\n' | '\t')
            || (' '..='\u{7e}').contains(&c)
            || c > '\u{9f}' && c < '\u{fffe}' && !bidi_control(c)
            || c > '\u{ffff}'));
        // A right-to-left override (or any bidirectional control) is shown, never obeyed.
        assert_eq!(printable("profile \u{202E}txt.exe"), "profile \\u{202E}txt.exe");
        assert_eq!(printable("\u{2066}a\u{2069}\u{200F}\u{061C}"), "\\u{2066}a\\u{2069}\\u{200F}\\u{061C}");
    }
}

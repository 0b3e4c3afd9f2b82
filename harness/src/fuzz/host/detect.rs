//! Crash reports on a host's stderr: AddressSanitizer, Rust panics, Python tracebacks, each
//! turned into a stable signature (kind plus top frames) for deduplication.

/// A crash report found on stderr.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CrashReport {
    /// `asan`, `panic` or `python`.
    pub kind: &'static str,
    /// Stable across runs of the same bug: the report's kind and its top frames, no addresses.
    pub signature: String,
    /// The report's first line, for people.
    pub headline: String,
}

/// How many frames a signature keeps.
const TOP_FRAMES: usize = 3;

/// Finds the first crash report on `stderr`.
pub fn crash_report(stderr: &str) -> Option<CrashReport> {
    asan(stderr).or_else(|| panic(stderr)).or_else(|| python(stderr))
}

fn asan(s: &str) -> Option<CrashReport> {
    let start = s.find("ERROR: AddressSanitizer:")?;
    let rest = &s[start..];
    let headline = rest.lines().next().unwrap_or_default().trim().to_string();
    let what = headline
        .trim_start_matches("ERROR: AddressSanitizer:")
        .split_whitespace()
        .next()
        .unwrap_or("unknown")
        .to_string();
    let frames: Vec<String> = rest
        .lines()
        .filter_map(|l| {
            let l = l.trim_start();
            l.strip_prefix('#')?;
            let f = l.split(" in ").nth(1)?.split_whitespace().next()?;
            Some(f.to_string())
        })
        .filter(|f| !f.starts_with("__asan") && !f.starts_with("__interceptor") && !f.starts_with("__interception"))
        .take(TOP_FRAMES)
        .collect();
    Some(CrashReport { kind: "asan", signature: format!("asan {what} in {}", frames.join(" < ")), headline })
}

fn panic(s: &str) -> Option<CrashReport> {
    let line = s.lines().find(|l| l.contains("panicked at "))?;
    let at = line.split("panicked at ").nth(1)?.trim_end_matches(':');
    // file:line:column; the column is dropped, the line kept.
    let mut parts: Vec<&str> = at.rsplitn(3, ':').collect();
    parts.reverse();
    let place = if parts.len() == 3 { format!("{}:{}", parts[0], parts[1]) } else { at.to_string() };
    Some(CrashReport { kind: "panic", signature: format!("panic at {place}"), headline: line.trim().to_string() })
}

fn python(s: &str) -> Option<CrashReport> {
    let start = s.rfind("Traceback (most recent call last):")?;
    let tb = &s[start..];
    let mut frames = Vec::new();
    let mut exception = None;
    for l in tb.lines().skip(1) {
        let t = l.trim_start();
        if let Some(f) = t.strip_prefix("File \"") {
            let file = f.split('"').next().unwrap_or_default();
            let base = file.rsplit('/').next().unwrap_or(file);
            let func = t.rsplit(", in ").next().unwrap_or("?");
            frames.push(format!("{base}:{func}"));
        } else if !l.starts_with(' ') && !t.is_empty() {
            exception = Some(t.to_string());
            break;
        }
    }
    let exception = exception.unwrap_or_else(|| "unknown exception".into());
    let ty = exception.split(':').next().unwrap_or_default().to_string();
    let top: Vec<String> = frames.iter().rev().take(TOP_FRAMES).cloned().collect();
    Some(CrashReport { kind: "python", signature: format!("python {ty} in {}", top.join(" < ")), headline: exception })
}

/// The name of a signal number (`SIGSEGV`), or its number.
pub fn signal_name(sig: i32) -> String {
    nix::sys::signal::Signal::try_from(sig).map_or_else(|_| format!("signal {sig}"), |s| s.as_str().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asan_reports_keep_the_top_frames_without_addresses() {
        let s = "noise\n=================================================================\n==123==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7ffd at pc 0x55 bp 0x7f sp 0x7f\nWRITE of size 1 at 0x7ffd thread T0\n    #0 0x55d in read_line /tmp/host.c:20\n    #1 0x55e in main /tmp/host.c:40\n    #2 0x7f1 in __libc_start_main\n";
        let r = crash_report(s).unwrap();
        assert_eq!(r.signature, "asan stack-buffer-overflow in read_line < main < __libc_start_main");
    }

    #[test]
    fn panics_and_tracebacks() {
        let p = "thread 'main' panicked at src/main.rs:10:5:\nindex out of bounds\n";
        assert_eq!(crash_report(p).unwrap().signature, "panic at src/main.rs:10");
        let t = "Traceback (most recent call last):\n  File \"/x/host.py\", line 30, in <module>\n    main()\n  File \"/x/host.py\", line 12, in parse\n    return int(x)\nValueError: invalid literal for int()\n";
        let r = crash_report(t).unwrap();
        assert_eq!(r.signature, "python ValueError in host.py:parse < host.py:<module>");
        assert_eq!(crash_report("all fine\n"), None);
        assert_eq!(signal_name(11), "SIGSEGV");
    }
}

//! Crash reports on a host's stderr: AddressSanitizer, Rust panics, Python tracebacks, each
//! turned into a stable signature for deduplication: its kind and the place that raised it
//! (the innermost frame; the callers that led there are not part of it, so one habit reached
//! from two call sites is one finding).

/// A crash report found on stderr.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CrashReport {
    /// `asan`, `panic` or `python`.
    pub kind: &'static str,
    /// Stable across runs of the same bug: the report's kind and where it was raised (the
    /// innermost frame, no address or line), never the callers that led there.
    pub signature: String,
    /// The report's first line, for people.
    pub headline: String,
}

/// How many frames a hang's stack keeps (for people; its signature is the first).
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
    // Frames of the first stack only (the access's, not the allocation's), the sanitizer's
    // own left out, with whether each is a shared library's (`(/lib/…/libc.so.6+0x…)`): the
    // innermost of the host's own is where it made the bad access (a `strcpy` intercepted in
    // the sanitizer's library was given a bad buffer by its caller).
    let frames: Vec<(String, bool)> = rest
        .lines()
        .skip(1)
        .map(str::trim_start)
        .skip_while(|l| !l.starts_with('#'))
        .take_while(|l| l.starts_with('#'))
        .filter_map(|l| {
            let mut words = l.split(" in ").nth(1)?.split_whitespace();
            let func = words.next()?.to_string();
            let library = words.next().is_some_and(|w| w.contains(".so"));
            Some((func, library))
        })
        .filter(|(f, _)| {
            !f.starts_with("__asan") && !f.starts_with("__interceptor") && !f.starts_with("__interception")
        })
        .collect();
    let own = frames.iter().position(|(_, lib)| !lib).unwrap_or(0);
    let frames: Vec<String> = frames.into_iter().skip(own).map(|(f, _)| f).collect();
    let site = frames.first().map_or("?", String::as_str);
    let headline = match frames.get(1) {
        Some(caller) => format!("{headline} (in {site}, called from {caller})"),
        None => headline,
    };
    Some(CrashReport { kind: "asan", signature: format!("asan {what} in {site}"), headline })
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
    // Outermost first, as a traceback lists them.
    let mut frames = Vec::new();
    let mut exception = None;
    for l in tb.lines().skip(1) {
        let t = l.trim_start();
        if let Some(f) = t.strip_prefix("File \"") {
            let file = f.split('"').next().unwrap_or_default();
            let base = file.rsplit('/').next().unwrap_or(file);
            let func = t.rsplit(", in ").next().unwrap_or("?");
            frames.push((format!("{base}:{func}"), python_library(file)));
        } else if !l.starts_with(' ') && !t.is_empty() {
            exception = Some(t.to_string());
            break;
        }
    }
    let exception = exception.unwrap_or_else(|| "unknown exception".into());
    let ty = exception.split(':').next().unwrap_or_default().to_string();
    // Where it was raised: in the host's own code, the bug is there; in a library (pyserial's
    // read when the port went away), the host's bug is that it does not handle what the
    // library raises, one habit however many of its call sites it escapes from.
    let site = frames.last().map_or("?", |(f, _)| f.as_str());
    let mut headline = exception.clone();
    if frames.last().is_some_and(|(_, lib)| *lib)
        && let Some((own, _)) = frames.iter().rev().find(|(_, lib)| !lib)
    {
        headline = format!("{exception} (raised in {site}, called from {own})");
    }
    Some(CrashReport { kind: "python", signature: format!("python {ty} in {site}"), headline })
}

/// Whether a Python frame's file is the interpreter's or an installed package's, not the
/// host's own code.
fn python_library(file: &str) -> bool {
    file.contains("/lib/python") || file.contains("-packages/") || file.starts_with('<')
}

/// Where a hung host was stuck: its innermost frames, its own code first.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct HangStack {
    /// How it was taken: `faulthandler` (Python), `eu-stack` or `gdb` (native).
    pub by: String,
    /// The top frames, no addresses or line numbers (`read_line < main`,
    /// `host.py:read_prompt < host.py:main`).
    pub frames: String,
}

impl HangStack {
    /// Where it waits: the innermost frame of the host's own code. The signature of a hang,
    /// so that one wait without a deadline is one finding whatever the path that led to it.
    pub fn site(&self) -> &str {
        self.frames.split(" < ").next().unwrap_or(&self.frames)
    }
}

/// Frames of a Python `faulthandler` dump (`File "x.py", line 12 in read_prompt`, most recent
/// first) of the thread that was current, or of the first thread listed; the host's own
/// files before the standard library and installed packages (where a read blocks).
pub fn faulthandler_frames(dump: &str) -> Option<String> {
    let start = dump.find("Current thread").or_else(|| dump.find("Thread 0x")).or_else(|| dump.find("Stack ("))?;
    let mut all = Vec::new();
    for l in dump[start..].lines().skip(1) {
        let t = l.trim_start();
        let Some(f) = t.strip_prefix("File \"") else { break };
        let file = f.split('"').next().unwrap_or_default();
        let func = t.rsplit(" in ").next().unwrap_or("?").trim();
        let base = file.rsplit('/').next().unwrap_or(file);
        all.push((format!("{base}:{func}"), python_library(file)));
    }
    own_first(all)
}

/// Frames of a native stack as `eu-stack -m` (`#1 0x… read_line - /path/exe`) or `gdb -batch
/// -ex bt` (`#1  0x… in read_line (fd=3) at host.c:20`, `from /lib/…` for a library) print
/// them, for the first thread listed; the program's own frames before those of shared
/// libraries (libc's `read`, the sanitizer's interceptors).
pub fn native_frames(text: &str) -> Option<String> {
    let mut all = Vec::new();
    let mut seen_thread = false;
    for l in text.lines() {
        let t = l.trim();
        if t.starts_with("TID ") || t.starts_with("Thread ") {
            if seen_thread && !all.is_empty() {
                break;
            }
            seen_thread = true;
            continue;
        }
        let Some(rest) = t.strip_prefix('#') else { continue };
        // Skip the frame number and the address.
        let mut words = rest.split_whitespace().skip(1).peekable();
        if words.peek().is_some_and(|w| w.starts_with("0x")) {
            words.next();
        }
        if words.peek() == Some(&"in") {
            words.next();
        }
        let Some(func) = words.next() else { continue };
        let func = func.split('(').next().unwrap_or(func).to_string();
        if func.is_empty() || func == "??" {
            continue;
        }
        let tail: Vec<&str> = words.collect();
        let module = tail.windows(2).find(|w| w[0] == "-" || w[0] == "from").map(|w| w[1]).unwrap_or_default();
        let library = module.contains(".so")
            || func.starts_with("__")
            || ["std::", "<std::", "core::", "<core::", "alloc::", "<alloc::", "<&"]
                .iter()
                .any(|p| func.starts_with(p))
            || func.starts_with("_dl_")
            // A Rust v0 symbol left mangled (eu-stack) in the standard library's crates.
            || (func.starts_with("_R") && ["_3std", "_4core", "_5alloc"].iter().any(|c| func.contains(c)))
            || [
                "read",
                "poll",
                "select",
                "pselect",
                "ppoll",
                "nanosleep",
                "clock_nanosleep",
                "epoll_wait",
                "sleep",
                "usleep",
            ]
            .contains(&func.as_str());
        all.push((func, library));
    }
    own_first(all)
}

fn own_first(all: Vec<(String, bool)>) -> Option<String> {
    if all.is_empty() {
        return None;
    }
    let own: Vec<&String> = all.iter().filter(|(_, lib)| !lib).map(|(f, _)| f).collect();
    let pick: Vec<&String> = if own.is_empty() { all.iter().map(|(f, _)| f).collect() } else { own };
    Some(pick.into_iter().take(TOP_FRAMES).cloned().collect::<Vec<_>>().join(" < "))
}

/// Samples the stack of a stopped-in-place native process with `gdb -batch` or, failing that,
/// `eu-stack` (each when installed; each given 10 s). `None` when neither is there, the
/// process cannot be traced, or no frame could be read.
pub fn sample_native(pid: i32) -> Option<HangStack> {
    // gdb first: it demangles Rust's v0 symbols (`_RNv…`), which eu-stack prints raw.
    let tools: [(&str, Vec<String>); 2] = [
        ("gdb", vec!["-batch".into(), "-nx".into(), "-p".into(), pid.to_string(), "-ex".into(), "bt".into()]),
        ("eu-stack", vec!["-m".into(), "-p".into(), pid.to_string()]),
    ];
    for (tool, args) in tools {
        let Some(out) = run_bounded(tool, &args, std::time::Duration::from_secs(10)) else { continue };
        if let Some(frames) = native_frames(&out) {
            return Some(HangStack { by: tool.to_string(), frames });
        }
    }
    None
}

/// Runs a tool with a deadline; its stdout, or `None` when it is missing or overran.
fn run_bounded(tool: &str, args: &[String], limit: std::time::Duration) -> Option<String> {
    use std::io::Read;
    let mut child = std::process::Command::new(tool)
        .args(args)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .ok()?;
    let mut out = child.stdout.take()?;
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out.by_ref().take(1 << 20).read_to_end(&mut s);
        s
    });
    let end = std::time::Instant::now() + limit;
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if std::time::Instant::now() < end => std::thread::sleep(std::time::Duration::from_millis(20)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
        }
    }
    reader.join().ok().map(|s| String::from_utf8_lossy(&s).into_owned())
}

/// The name of a signal number (`SIGSEGV`), or its number.
pub fn signal_name(sig: i32) -> String {
    nix::sys::signal::Signal::try_from(sig).map_or_else(|_| format!("signal {sig}"), |s| s.as_str().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asan_reports_are_signed_by_the_hosts_frame_nearest_the_bad_access() {
        let s = "noise\n=================================================================\n==123==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7ffd at pc 0x55 bp 0x7f sp 0x7f\nWRITE of size 1 at 0x7ffd thread T0\n    #0 0x55d in read_line /tmp/host.c:20\n    #1 0x55e in main /tmp/host.c:40\n    #2 0x7f1 in __libc_start_main\n";
        let r = crash_report(s).unwrap();
        assert_eq!(r.signature, "asan stack-buffer-overflow in read_line");
        // The same bad access reached from another caller is the same finding.
        let other = s.replace("main /tmp/host.c:40", "parse_answer /tmp/host.c:60");
        assert_eq!(crash_report(&other).unwrap().signature, r.signature);
        assert!(crash_report(&other).unwrap().headline.ends_with("(in read_line, called from parse_answer)"));
        // A libc function the sanitizer intercepts was handed the bad buffer by the host's
        // code: that is where it is signed. The allocation's stack is not read.
        let strcpy = "==9==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7ffd\nWRITE of size 9 at 0x7ffd thread T0\n    #0 0x7f1 in strcpy (/lib/x86_64-linux-gnu/libasan.so.8+0x5e)\n    #1 0x55d in copy_name /tmp/host.c:12\n    #2 0x55e in main /tmp/host.c:40\n\n0x7ffd is located in stack of thread T0\n    #0 0x55f in other_place /tmp/host.c:3\n";
        assert_eq!(crash_report(strcpy).unwrap().signature, "asan stack-buffer-overflow in copy_name");
    }

    /// A Python exception is signed by its type and where it was raised, not by the callers:
    /// pyserial's `SerialException` on a hang-up is one finding whether the host's helper or
    /// its main loop was reading; two types, or two raising places, stay two.
    #[test]
    fn one_exception_from_one_place_is_one_signature_whatever_the_caller() {
        let tb = |caller: &str| {
            format!(
                "Traceback (most recent call last):\n  File \"/h/host.py\", line 40, in <module>\n    main()\n{caller}  File \"/usr/lib/python3/site-packages/serial/serialposix.py\", line 595, in read\n    raise SerialException(\nserial.serialutil.SerialException: device reports readiness to read but returned no data\n"
            )
        };
        let helper =
            crash_report(&tb("  File \"/h/gclhost.py\", line 31, in read_until\n    buf += port.read(1)\n")).unwrap();
        let direct =
            crash_report(&tb("  File \"/h/host.py\", line 19, in scenario\n    block = port.read(10)\n")).unwrap();
        assert_eq!(helper.signature, "python serial.serialutil.SerialException in serialposix.py:read");
        assert_eq!(direct.signature, helper.signature);
        assert!(
            helper.headline.ends_with("(raised in serialposix.py:read, called from gclhost.py:read_until)"),
            "{}",
            helper.headline
        );
        let raised_here = |func: &str, ty: &str| {
            format!(
                "Traceback (most recent call last):\n  File \"/h/host.py\", line 40, in <module>\n    main()\n  File \"/h/host.py\", line 9, in {func}\n    x = t[k]\n{ty}: 3\n"
            )
        };
        let a = crash_report(&raised_here("decode", "IndexError")).unwrap();
        assert_eq!(a.signature, "python IndexError in host.py:decode");
        assert_ne!(crash_report(&raised_here("decode", "KeyError")).unwrap().signature, a.signature);
        assert_ne!(crash_report(&raised_here("parse", "IndexError")).unwrap().signature, a.signature);
    }

    #[test]
    fn panics_and_tracebacks() {
        let p = "thread 'main' panicked at src/main.rs:10:5:\nindex out of bounds\n";
        assert_eq!(crash_report(p).unwrap().signature, "panic at src/main.rs:10");
        let t = "Traceback (most recent call last):\n  File \"/x/host.py\", line 30, in <module>\n    main()\n  File \"/x/host.py\", line 12, in parse\n    return int(x)\nValueError: invalid literal for int()\n";
        let r = crash_report(t).unwrap();
        assert_eq!(r.signature, "python ValueError in host.py:parse");
        assert_eq!(crash_report("all fine\n"), None);
        assert_eq!(signal_name(11), "SIGSEGV");
    }

    #[test]
    fn hang_stacks_name_the_hosts_own_code() {
        let py = "Fatal Python error: Aborted\n\nCurrent thread 0x00007f (most recent call first):\n  File \"/usr/lib/python3/dist-packages/serial/serialposix.py\", line 565 in read\n  File \"/t/hosts/py_host.py\", line 20 in read_prompt\n  File \"/t/hosts/py_host.py\", line 40 in main\n  File \"/t/hosts/py_host.py\", line 44 in <module>\n\nExtension modules: x\n";
        assert_eq!(faulthandler_frames(py).unwrap(), "py_host.py:read_prompt < py_host.py:main < py_host.py:<module>");
        let eu = "PID 12 - process\nTID 12:\n#0  0x00007f3 __GI___libc_read - /usr/lib/x86_64-linux-gnu/libc.so.6\n#1  0x0000555 read_line - /tmp/c_host\n#2  0x0000556 main - /tmp/c_host\n#3  0x00007f4 __libc_start_call_main - /usr/lib/x86_64-linux-gnu/libc.so.6\n";
        assert_eq!(native_frames(eu).unwrap(), "read_line < main");
        let gdb = "0x00007f in __GI___libc_read (fd=3, buf=0x7ff, nbytes=1) at ../sysdeps/unix/sysv/linux/read.c:26\n#0  0x00007f in __GI___libc_read (fd=3) at ../sysdeps/read.c:26\n#1  0x000055 in read_line (fd=3, buf=0x7ff \"\") at host.c:20\n#2  0x000055 in main () at host.c:40\n";
        assert_eq!(native_frames(gdb).unwrap(), "read_line < main");
        assert_eq!(native_frames("no frames here"), None);
    }
}

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
    // Whether the innermost frame is pyserial's.
    let mut raised_in_pyserial = false;
    for l in tb.lines().skip(1) {
        let t = l.trim_start();
        if let Some(f) = t.strip_prefix("File \"") {
            let file = f.split('"').next().unwrap_or_default();
            let base = file.rsplit('/').next().unwrap_or(file);
            let func = t.rsplit(", in ").next().unwrap_or("?");
            frames.push((format!("{base}:{func}"), python_library(file)));
            raised_in_pyserial = file.contains("/serial/");
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
    if raised_in_pyserial && hang_up(&exception) {
        // One event, the port going away, which pyserial raises as a `SerialException` from
        // `read`, an `OSError` from `in_waiting`, or a failed `write`, depending on which call
        // the host was in when it came. The host's bug is the same whichever: it does not
        // handle a port that went away.
        return Some(CrashReport {
            kind: "python",
            signature: "python port hang-up (pyserial) not handled".into(),
            headline: format!("the port went away: {headline}"),
        });
    }
    Some(CrashReport { kind: "python", signature: format!("python {ty} in {site}"), headline })
}

/// Whether an exception pyserial raised says the port went away (the other end hung up, the
/// device is gone): EIO, a read of nothing where select said there was data, a closed or
/// reset socket, a broken pipe. Not a port the host closed itself (`PortNotOpenError`), a
/// timeout, or a bad setting.
fn hang_up(exception: &str) -> bool {
    [
        "[Errno 5]",
        "Input/output error",
        "returned no data",
        "device disconnected",
        "socket disconnected",
        "[Errno 32]",
        "Broken pipe",
        "[Errno 104]",
        "Connection reset",
        "device reports error (poll)",
    ]
    .iter()
    .any(|m| exception.contains(m))
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
    /// A Python host blocked for ever inside one pyserial call (it did not wake while it was
    /// watched): that call (`serialposix.py:read`) and the host's program (`host.py`, the file
    /// of its outermost own frame). See [`HangStack::site`].
    #[serde(default)]
    pub blocked_in: Option<PortCall>,
}

/// A pyserial call a Python host was blocked in, and the host's program.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PortCall {
    /// The call, `serialposix.py:read`.
    pub call: String,
    /// The file of the host's outermost own frame, `host.py`.
    pub program: String,
}

impl HangStack {
    /// Where it waits, the signature of a hang:
    /// - a Python host blocked for ever in a pyserial call: that call, in the host's program
    ///   (`host.py, blocked in serialposix.py:read`). pyserial's calls take no deadline of
    ///   their own; their deadline is the port's (`timeout`, `write_timeout`), set once for
    ///   every call on it. So a port without a timeout is one bug however many of the host's
    ///   functions (its own loop, a helper with a deadline the blocking read never lets it
    ///   check) read from it, and it is mended in one place;
    /// - else the innermost frame of the host's own code: a native `read(2)`, a loop that
    ///   polls a port with a timeout but has no deadline of its own, take their deadline (or
    ///   lack of one) from that code, so one wait without a deadline is one finding whatever
    ///   the path that led to it.
    pub fn site(&self) -> String {
        match &self.blocked_in {
            Some(b) => format!("{}, blocked in {}", b.program, b.call),
            None => self.frames.split(" < ").next().unwrap_or(&self.frames).to_string(),
        }
    }
}

/// The pyserial call a Python `faulthandler` dump is in, when its innermost frame is
/// pyserial's, with the host's program (see [`HangStack::site`]).
pub fn faulthandler_port_call(dump: &str) -> Option<PortCall> {
    let frames = python_dump_frames(dump)?;
    let (file, func) = frames.first()?;
    if !file.contains("/serial/") {
        return None;
    }
    let base = |f: &str| f.rsplit('/').next().unwrap_or(f).to_string();
    let program = frames.iter().rev().find(|(f, _)| !python_library(f)).map(|(f, _)| base(f))?;
    Some(PortCall { call: format!("{}:{func}", base(file)), program })
}

/// The (file, function) frames of a `faulthandler` dump, innermost first, of the thread that
/// was current, or of the first thread listed.
fn python_dump_frames(dump: &str) -> Option<Vec<(String, String)>> {
    let start = dump.find("Current thread").or_else(|| dump.find("Thread 0x")).or_else(|| dump.find("Stack ("))?;
    let mut all = Vec::new();
    for l in dump[start..].lines().skip(1) {
        let t = l.trim_start();
        let Some(f) = t.strip_prefix("File \"") else { break };
        let file = f.split('"').next().unwrap_or_default().to_string();
        let func = t.rsplit(" in ").next().unwrap_or("?").trim().to_string();
        all.push((file, func));
    }
    Some(all)
}

/// Frames of a Python `faulthandler` dump (`File "x.py", line 12 in read_prompt`, most recent
/// first) of the thread that was current, or of the first thread listed; the host's own
/// files before the standard library and installed packages (where a read blocks).
pub fn faulthandler_frames(dump: &str) -> Option<String> {
    let all = python_dump_frames(dump)?
        .into_iter()
        .map(|(file, func)| {
            let base = file.rsplit('/').next().unwrap_or(&file).to_string();
            (format!("{base}:{func}"), python_library(&file))
        })
        .collect();
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
            return Some(HangStack { by: tool.to_string(), frames, blocked_in: None });
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
    /// pyserial's `PortNotOpenError` is one finding whether the host's helper or its main loop
    /// was reading; two types, or two raising places, stay two.
    #[test]
    fn one_exception_from_one_place_is_one_signature_whatever_the_caller() {
        let not_open = "serial.serialutil.PortNotOpenError: Attempting to use a port that is not open";
        let helper = crash_report(&pyserial_tb("gclhost.py\", line 31, in read_until", "read", not_open)).unwrap();
        let direct = crash_report(&pyserial_tb("host.py\", line 19, in scenario", "read", not_open)).unwrap();
        assert_eq!(helper.signature, "python serial.serialutil.PortNotOpenError in serialposix.py:read");
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

    /// A traceback of an exception raised in pyserial's `serialposix.py` function `func`,
    /// called from the host's frame `caller` (`file", line N, in function`).
    fn pyserial_tb(caller: &str, func: &str, exception: &str) -> String {
        format!(
            "Traceback (most recent call last):\n  File \"/h/host.py\", line 40, in <module>\n    main()\n  File \"/h/{caller}\n    buf += port.read(1)\n  File \"/usr/lib/python3/site-packages/serial/serialposix.py\", line 595, in {func}\n    raise X\n{exception}\n"
        )
    }

    /// A port that went away is one event, which pyserial raises as a `SerialException` from
    /// `read` or an `OSError` from `in_waiting` (or a failed `write`) depending on the call
    /// the host was in: one finding. An exception of the host's own, or another of pyserial's,
    /// is not merged with it.
    #[test]
    fn a_hang_up_is_one_signature_whatever_pyserial_raised_it_as() {
        let read = crash_report(&pyserial_tb(
            "host.py\", line 19, in scenario",
            "read",
            "serial.serialutil.SerialException: device reports readiness to read but returned no data (device disconnected or multiple access on port?)",
        ))
        .unwrap();
        let waiting = crash_report(&pyserial_tb(
            "gclhost.py\", line 31, in read_until",
            "in_waiting",
            "OSError: [Errno 5] Input/output error",
        ))
        .unwrap();
        let write = crash_report(&pyserial_tb(
            "host.py\", line 12, in send",
            "write",
            "serial.serialutil.SerialException: write failed: [Errno 5] Input/output error",
        ))
        .unwrap();
        assert_eq!(read.signature, "python port hang-up (pyserial) not handled");
        assert_eq!(waiting.signature, read.signature);
        assert_eq!(write.signature, read.signature);
        assert!(waiting.headline.contains("OSError") && waiting.headline.contains("gclhost.py:read_until"));
        let index = "Traceback (most recent call last):\n  File \"/h/host.py\", line 9, in decode\n    x = t[k]\nIndexError: list index out of range\n";
        assert_eq!(crash_report(index).unwrap().signature, "python IndexError in host.py:decode");
        let not_open = "serial.serialutil.PortNotOpenError: Attempting to use a port that is not open";
        assert_ne!(
            crash_report(&pyserial_tb("host.py\", line 19, in scenario", "read", not_open)).unwrap().signature,
            read.signature
        );
        // An EIO the host's own code met (its own `os.read`) is its own raise site, not
        // pyserial's hang-up.
        let own = "Traceback (most recent call last):\n  File \"/h/host.py\", line 9, in pump\n    os.read(fd, 1)\nOSError: [Errno 5] Input/output error\n";
        assert_eq!(crash_report(own).unwrap().signature, "python OSError in host.py:pump");
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

    /// A Python host blocked for ever in pyserial's read, reached from its own loop or from a
    /// helper whose deadline the blocking read never lets it check, is one hang: its port has
    /// no timeout. One that was not blocked in a pyserial call is signed by its own frame.
    #[test]
    fn a_python_host_blocked_in_pyserial_is_signed_by_the_call_in_its_program() {
        let dump = |own: &str| {
            format!(
                "Fatal Python error: Aborted\n\nCurrent thread 0x00007f (most recent call first):\n  File \"/usr/lib/python3/site-packages/serial/serialposix.py\", line 565 in read\n{own}  File \"/t/prompt_forever.py\", line 20 in scenario\n  File \"/t/gclhost.py\", line 70 in main\n  File \"/t/prompt_forever.py\", line 24 in <module>\n\n"
            )
        };
        let stack = |d: &str| HangStack {
            by: "faulthandler".into(),
            frames: faulthandler_frames(d).unwrap(),
            blocked_in: faulthandler_port_call(d),
        };
        let own_loop = stack(&dump("  File \"/t/prompt_forever.py\", line 12 in command\n"));
        let helper = stack(&dump("  File \"/t/gclhost.py\", line 31 in read_until\n"));
        assert_eq!(own_loop.site(), "prompt_forever.py, blocked in serialposix.py:read");
        assert_eq!(helper.site(), own_loop.site());
        assert!(helper.frames.starts_with("gclhost.py:read_until"), "{}", helper.frames);
        // Not blocked (the port has a timeout; its loop has no deadline): its own frame.
        let looping = HangStack { blocked_in: None, ..own_loop.clone() };
        assert_eq!(looping.site(), "prompt_forever.py:command");
        // Not in pyserial: no port call.
        let sleeping = "Current thread 0x1 (most recent call first):\n  File \"/t/host.py\", line 3 in wait\n  File \"/t/host.py\", line 9 in <module>\n\n";
        assert_eq!(faulthandler_port_call(sleeping), None);
    }
}

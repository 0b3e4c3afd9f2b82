//! Crash reports on a host's stderr: AddressSanitizer, Rust panics, Python tracebacks, each
//! turned into a stable signature for deduplication: its kind and the place that raised it
//! (the innermost frame; the callers that led there are not part of it, so one habit reached
//! from two call sites is one finding).
//!
//! A port that went away, whichever exception pyserial raised it as, is one "hang-up not handled".
//! A sanitizer report is signed by the host's first own frame: the system's frames (libc,
//! libstdc++, Boost, the sanitizer's interceptors) are told apart by the object file a frame
//! comes from, when the stack names it, and by their function's name or namespace; never by
//! the folders of a source path, which are the host's to name. A C++ runtime's "terminate
//! called" is signed by what was thrown and where. Hang stacks (faulthandler,
//! eu-stack, gdb) are read into the frame of the host's own code that waits: a Python host blocked
//! for ever in a pyserial call is signed by that call in its program (a pyserial port's deadline is
//! its timeout, one setting for every read).

/// A crash report found on stderr.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CrashReport {
    /// `c++` (an exception nobody caught), `asan`, `panic` or `python`.
    pub kind: &'static str,
    /// Stable across runs of the same bug: the report's kind and where it was raised (the
    /// innermost frame, no address or line), never the callers that led there.
    pub signature: String,
    /// The report's first line, for people.
    pub headline: String,
}

/// How many frames a hang's stack keeps (for people; its signature is the first).
const TOP_FRAMES: usize = 3;

/// Finds the first crash report on `stderr`: a C++ runtime's message about an exception nobody
/// caught (with where it was thrown when a sanitizer printed the stack), an AddressSanitizer
/// report, a Rust panic, a Python traceback.
pub fn crash_report(stderr: &str) -> Option<CrashReport> {
    uncaught(stderr).or_else(|| asan(stderr)).or_else(|| panic(stderr)).or_else(|| python(stderr))
}

/// One frame of a native stack as a sanitizer, gdb or eu-stack prints it: the function (its
/// parameters left out) and the object file it comes from, when the stack names it (a
/// sanitizer's `(libc.so.6+0x29d90)`, gdb's `from /lib/...`, eu-stack's module); a frame
/// printed with its source file names no object file.
#[derive(Debug, Clone, PartialEq, Eq)]
struct NativeFrame {
    func: String,
    module: Option<String>,
}

impl NativeFrame {
    /// Whether it is the code of the system rather than the host's own (see [`system_frame`]).
    fn system(&self) -> bool {
        system_frame(&self.func, self.module.as_deref())
    }
}

/// Whether a frame is the code of the system rather than the host's own: the C library and
/// the loader, the C++ and Rust runtimes, the sanitizers' runtime and interceptors, and the
/// libraries a host is built on (Boost, Poco, ROS), told by the object file it comes from
/// (`module`, when the stack names it) or by its function's name or namespace. Never by the
/// words of a source path: the host's own code may live in a folder named `csu/`, `libio/` or
/// `boost/` as well as glibc's or Boost's does (such a host was signed `in ?`). A host's own
/// shared library (`libbarrett.so`) is the host's.
fn system_frame(func: &str, module: Option<&str>) -> bool {
    const MODULES: &[&str] = &[
        "libc.so",
        "libc-",
        "libstdc++",
        "libc++",
        "libgcc_s",
        "libm.so",
        "libm-",
        "libpthread",
        "ld-linux",
        "libdl",
        "librt",
        "libasan",
        "libubsan",
        "liblsan",
        "libtsan",
        "libhwasan",
        "libclang_rt",
        "libunwind",
        "libboost_",
        "libPoco",
    ];
    const NAMESPACES: &[&str] = &[
        "std::",
        "<std::",
        "__gnu_cxx::",
        "__cxxabiv1::",
        "boost::",
        "<boost::",
        "void boost::",
        "Poco::",
        "asio::",
        "ros::",
        "rclcpp::",
        "core::",
        "<core::",
        "alloc::",
        "<alloc::",
        "<&",
    ];
    // Functions of the C library and of the sanitizers' runtime, for a stack that says no
    // more than their names.
    const NAMES: &[&str] = &[
        "read",
        "write",
        "poll",
        "ppoll",
        "select",
        "pselect",
        "nanosleep",
        "clock_nanosleep",
        "epoll_wait",
        "epoll_pwait",
        "sleep",
        "usleep",
        "syscall",
        "recv",
        "recvfrom",
        "recvmsg",
        "accept",
        "accept4",
        "connect",
        "fgets",
        "fgetc",
        "getc",
        "fread",
        "getline",
        "getdelim",
        "waitpid",
        "raise",
        "abort",
        "pthread_cond_wait",
        "pthread_join",
        "sem_wait",
        "scanf_common",
        "printf_common",
        // What the sanitizers intercept, as newer ones name their interceptors.
        "strcpy",
        "strncpy",
        "strcat",
        "strncat",
        "strlen",
        "memcpy",
        "memmove",
        "memset",
        "sprintf",
        "vsprintf",
        "snprintf",
        "vsnprintf",
        "sscanf",
        "vsscanf",
        "malloc",
        "calloc",
        "realloc",
        "free",
        "_start",
        "??",
        // Where the C library starts a thread (gdb with libc's sources names no object file).
        "start_thread",
        "clone",
        "clone3",
    ];
    // A library installed with ROS, an address in no known object file.
    let system_module = |m: &str| {
        let file = m.rsplit('/').next().unwrap_or_default();
        MODULES.iter().any(|x| file.starts_with(x)) || m.starts_with("/opt/ros/") || m == "<unknown module>"
    };
    module.is_some_and(system_module)
        || NAMESPACES.iter().any(|n| func.starts_with(n))
        || NAMES.contains(&func)
        || func.starts_with("__")
        || func.starts_with("_dl_")
        || func.starts_with("_IO_")
        // The compiler's SIMD intrinsics (`_mm512_mask_testn_epi8_mask`): inlined from its
        // headers into the C library's string functions, where gdb shows them as frames of
        // their own above `__strstr_avx512` (a spinning host was signed by one).
        || ["_mm_", "_mm256_", "_mm512_"].iter().any(|p| func.starts_with(p))
        // A Rust v0 symbol left mangled (eu-stack) in the standard library's crates.
        || (func.starts_with("_R") && ["_3std", "_4core", "_5alloc"].iter().any(|c| func.contains(c)))
}

/// A function as a stack prints it, without its parameter list and ABI tag
/// (`Port::check(int, char const*)` → `Port::check`, `Port::read[abi:cxx11]()` → `Port::read`).
fn function_name(func: &str) -> String {
    let mut f = func.trim();
    if let Some(cut) = f.strip_suffix(" const") {
        f = cut.trim_end();
    }
    if f.ends_with(')')
        && let Some(open) = matching_open(f)
        && open > 0
    {
        f = f[..open].trim_end();
    }
    let f = f.split("[abi:").next().unwrap_or(f);
    trim_templates(f)
}

/// A function's name with each template argument list shown as `<…>`
/// (`reactive_socket_recv_op<boost::asio::mutable_buffers_1, …>::do_complete` →
/// `reactive_socket_recv_op<…>::do_complete`): a Boost frame's arguments ran to thousands of
/// characters in one message. `operator<`, `operator<<`, `operator->` stay; a name whose
/// brackets do not balance stays whole.
fn trim_templates(f: &str) -> String {
    let mut out = String::with_capacity(f.len());
    let mut depth = 0usize;
    for (i, c) in f.char_indices() {
        let operator = depth == 0 && (f[..i].ends_with("operator") || f[..i].ends_with("operator<"));
        match c {
            '<' if operator => out.push(c),
            '<' => {
                if depth == 0 {
                    out.push_str("<…>");
                }
                depth += 1;
            }
            '>' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    if depth == 0 { out } else { f.to_string() }
}

/// The index of the `(` that opens the parenthesised group `s` ends with.
fn matching_open(s: &str) -> Option<usize> {
    let mut depth = 0usize;
    for (i, c) in s.char_indices().rev() {
        match c {
            ')' => depth += 1,
            '(' => {
                depth = depth.checked_sub(1)?;
                if depth == 0 {
                    return Some(i);
                }
            }
            _ => {}
        }
    }
    None
}

/// A sanitizer's frame line (`#3 0x55 in hand_get /src/host.c:39`, `#5 0x7f in std::terminate()
/// (/lib/x86_64-linux-gnu/libstdc++.so.6+0xa8e84)`); `None` for a frame without a function.
fn sanitizer_frame(line: &str) -> Option<NativeFrame> {
    let rest = line.trim_start().strip_prefix('#')?;
    let (_, after) = rest.split_once(" in ")?;
    let after = after.trim();
    // Where it lives is the last word: a module and offset in parentheses, or a source path
    // with its line (which names no module).
    let (func, module) = match after.rsplit_once(' ') {
        Some((f, p)) if p.starts_with('(') && p.ends_with(')') => {
            let inner = &p[1..p.len() - 1];
            (f, Some(inner.rsplit_once('+').map_or(inner, |(m, _)| m).to_string()))
        }
        Some((f, p)) if p.contains('/') || source_line(p) => (f, None),
        _ => (after, None),
    };
    let func = function_name(func);
    (!func.is_empty()).then_some(NativeFrame { func, module })
}

/// Whether a word is a source file and line (`host.c:20`, `host.c:20:5`).
fn source_line(word: &str) -> bool {
    let mut parts = word.split(':');
    parts.next().is_some_and(|f| f.contains('.'))
        && parts.next().is_some_and(|l| !l.is_empty() && l.bytes().all(|b| b.is_ascii_digit()))
}

/// The frames of the first stack of a sanitizer report that starts at `report` (the bad
/// access's, not the allocation's), innermost first.
fn sanitizer_stack(report: &str) -> Vec<NativeFrame> {
    report
        .lines()
        .skip(1)
        .map(str::trim_start)
        .skip_while(|l| !l.starts_with('#'))
        .take_while(|l| l.starts_with('#'))
        .filter_map(sanitizer_frame)
        .collect()
}

/// Where a sanitizer report's bad access was made in the host's own code: the innermost frame
/// of its first stack that is not the system's (a `strcpy` or `sscanf` the sanitizer
/// intercepts was handed the bad buffer by its caller), with the system frames it went
/// through (`scanf_common < __interceptor___isoc99_sscanf`) and its caller. A stack overflow
/// through a libc call smashes the frames above the buffer, so the stack may end in the
/// interceptor: then the frame that owns the overflowed variable (`is located in stack of
/// thread T0 ... in frame #0 ... in hand_pget`) is the host's. So it is, first, in a report
/// taken with the fast unwinder (`owner_first`), which skips the frame that called an
/// interceptor (frame pointers link the frames only of code built with them).
fn own_site(report: &str, owner_first: bool) -> Option<(String, Option<String>, Option<String>)> {
    let frames = sanitizer_stack(report);
    let owner = report
        .find("is located in stack of thread")
        .and_then(|at| report[at..].lines().skip(1).find_map(sanitizer_frame))
        .filter(|f| !f.system());
    let own = frames.iter().position(|f| !f.system());
    let through = |upto: usize| {
        let sys: Vec<&str> = frames[..upto].iter().map(|f| f.func.as_str()).collect();
        (!sys.is_empty()).then(|| sys.join(" < "))
    };
    if owner_first && let Some(f) = &owner {
        let upto = own.unwrap_or(frames.len());
        return Some((f.func.clone(), through(upto), None));
    }
    match own {
        Some(i) => {
            let caller = frames[i + 1..].iter().find(|f| !f.system()).map(|f| f.func.clone());
            Some((frames[i].func.clone(), through(i), caller))
        }
        None => match owner {
            Some(f) => Some((f.func, through(frames.len()), None)),
            None => frames.first().map(|f| (f.func.clone(), None, None)),
        },
    }
}

/// The heading under which a run's stderr gets the AddressSanitizer report of a second run of
/// the same schedule, when the first report named no frame of the host's own code.
pub const ASAN_SECOND_RUN: &str = "--- AddressSanitizer's report in a second run of the same schedule ---";

/// The kind of an AddressSanitizer report (`stack-buffer-overflow`), from its first line.
fn asan_kind(report: &str) -> String {
    let line = report.lines().next().unwrap_or_default();
    let after = line.split("AddressSanitizer:").nth(1).unwrap_or_default();
    after.split_whitespace().next().unwrap_or("unknown").to_string()
}

/// Whether a sanitizer report names a frame of the host's own code: in its stack, or as the
/// frame whose variable overflowed.
fn names_own(report: &str) -> bool {
    sanitizer_stack(report).iter().any(|f| !f.system())
        || report
            .find("is located in stack of thread")
            .and_then(|at| report[at..].lines().skip(1).find_map(sanitizer_frame))
            .is_some_and(|f| !f.system())
}

/// Whether a report taken with AddressSanitizer's fast unwinder can be trusted to name the
/// host's frame: it names the frame whose variable overflowed, or its first frame is the host's
/// own. (The fast unwinder follows frame pointers, and skips the caller of an interceptor that
/// keeps none: a `sscanf` into a heap buffer reads `in main`, its caller lost.)
pub fn asan_fast_report_names_own(report: &str) -> bool {
    let owner = report
        .find("is located in stack of thread")
        .and_then(|at| report[at..].lines().skip(1).find_map(sanitizer_frame))
        .is_some_and(|f| !f.system());
    owner || sanitizer_stack(report).first().is_some_and(|f| !f.system())
}

/// The kind of stderr's AddressSanitizer report when it names no frame of the host's own code
/// and no second run completed it yet: its stack has no frame at all (the unwinder crashed on a
/// smashed stack: `nested bug in the same thread`), or only the system's (an overflow that ran
/// off the end of the stack inside `sscanf`: `stack-overflow` in `__vfscanf_internal`).
pub fn asan_without_frames(s: &str) -> Option<String> {
    let at = s.find("ERROR: AddressSanitizer:")?;
    if s.contains(ASAN_SECOND_RUN) {
        return None;
    }
    (!names_own(&s[at..])).then(|| asan_kind(&s[at..]))
}

fn asan(s: &str) -> Option<CrashReport> {
    let start = s.find("ERROR: AddressSanitizer:")?;
    // The first report, up to a second run's if there is one.
    let mut rest = &s[start..];
    if let Some(cut) = rest.find(ASAN_SECOND_RUN) {
        rest = &rest[..cut];
    }
    // A report naming none of the host's frames, completed by a second run's (see
    // `asan_without_frames`).
    let mut second = false;
    if !names_own(rest)
        && let Some(at) = s.find(ASAN_SECOND_RUN)
        && let Some(r) = s[at..].find("ERROR: AddressSanitizer:")
    {
        rest = &s[at + r..];
        second = true;
    }
    let headline = rest.lines().next().unwrap_or_default().trim().to_string();
    let what = asan_kind(rest);
    let (site, through, caller) = own_site(rest, second).unwrap_or_else(|| ("?".into(), None, None));
    let mut context = Vec::new();
    if let Some(t) = through {
        context.push(format!("through {t}"));
    }
    if let Some(c) = caller {
        context.push(format!("called from {c}"));
    }
    let headline = if site == "?" {
        format!("{headline} (the sanitizer printed no frame)")
    } else if second {
        let mut context = context;
        context.push("from a second run of the same schedule: the first run's report had no frame".into());
        format!("{headline} (in {site}, {})", context.join(", "))
    } else if context.is_empty() {
        format!("{headline} (in {site})")
    } else {
        format!("{headline} (in {site}, {})", context.join(", "))
    };
    Some(CrashReport { kind: "asan", signature: format!("asan {what} in {site}"), headline })
}

/// The heading under which a run's stderr gets the host's stack at SIGABRT, taken by gdb in a
/// second run of the same schedule.
pub const ABORT_STACK: &str = "--- the host's stack at SIGABRT (gdb, in a second run of the same schedule) ---";

/// The line a run's stderr gets instead of [`ABORT_STACK`] when no stack was taken, followed by
/// why (gdb missing, or no second run under it threw the same).
pub const ABORT_NO_STACK: &str = "--- no stack at SIGABRT: ";

/// The line after a gdb stack ([`ABORT_STACK`]) taken in a second run that threw the same type
/// with another `what()` (timing took it elsewhere), followed by that `what()`.
pub const ABORT_OTHER: &str = "--- that second run threw it with what(): ";

/// Whether stderr has a C++ runtime's message about an exception nobody caught.
pub fn uncaught_exception(stderr: &str) -> bool {
    uncaught(stderr).is_some()
}

/// A C++ runtime's last words about an exception nobody caught: libstdc++'s `terminate called
/// after throwing an instance of 'T'` and `what(): ...`, or libc++abi's `terminating due to
/// uncaught exception of type T: ...`. Signed by what was thrown and, when the stack at the
/// abort that follows is known ([`ABORT_STACK`], or a sanitizer's report of the SIGABRT), the
/// host's own frame that threw: one unhandled error from one place is one finding. What
/// `what()` said (an errno's text, which varies) is in the message.
fn uncaught(s: &str) -> Option<CrashReport> {
    let (ty, what) = thrown(s)?;
    // Where it was thrown: the stack gdb took at the abort (a second run of the same
    // schedule), else a sanitizer's at its SIGABRT handler.
    let site = s
        .find(ABORT_STACK)
        .and_then(|at| native_frames(&s[at + ABORT_STACK.len()..]))
        .and_then(|(own, _)| {
            let mut frames = own.split(" < ").map(String::from);
            let first = frames.next()?;
            Some((first, None, frames.next()))
        })
        .or_else(|| s.find("ERROR: AddressSanitizer:").and_then(|at| own_site(&s[at..], false)))
        .filter(|(f, _, _)| !system_frame(f, None));
    let mut signature = format!("uncaught C++ exception {ty}");
    let mut headline = format!("an exception nobody caught: {ty}");
    if let Some(w) = &what {
        headline += &format!(", what(): {}", crate::report::truncate_note(w, 200));
    }
    match &site {
        Some((f, _, caller)) => {
            signature += &format!(" in {f}");
            headline += &format!(" (thrown in {f}");
            if let Some(c) = caller {
                headline += &format!(", called from {c}");
            }
            if let Some(other) = s.find(ABORT_OTHER).and_then(|at| s[at + ABORT_OTHER.len()..].lines().next()) {
                let other = crate::report::truncate_note(other.trim(), 200);
                headline += &format!(", in a second run that threw it with what(): {other}");
            }
            headline.push(')');
        }
        None => match s.find(ABORT_NO_STACK).and_then(|at| s[at + ABORT_NO_STACK.len()..].lines().next()) {
            Some(why) => headline += &format!(" (where it was thrown: not known, {})", why.trim()),
            None => headline += " (where it was thrown: no stack, gdb took none)",
        },
    }
    Some(CrashReport { kind: "c++", signature, headline })
}

/// What a C++ runtime said went uncaught in `s` (the first such report): the type thrown and
/// its `what()`. A second run's stack places a crash only when that run threw the same.
pub fn thrown(s: &str) -> Option<(String, Option<String>)> {
    const GNU: &str = "terminate called after throwing an instance of '";
    const LLVM: &str = "terminating due to uncaught exception of type ";
    let (ty, what) = if let Some(at) = s.find(GNU) {
        let rest = &s[at + GNU.len()..];
        let ty = rest.split('\'').next().unwrap_or_default().to_string();
        let what = rest.lines().nth(1).and_then(|l| l.trim().strip_prefix("what():")).map(|w| w.trim().to_string());
        (ty, what)
    } else if let Some(at) = s.find(LLVM) {
        let line = s[at + LLVM.len()..].lines().next().unwrap_or_default();
        match line.split_once(": ") {
            Some((t, w)) => (t.trim().to_string(), Some(w.trim().to_string())),
            None => (line.trim().to_string(), None),
        }
    } else if s.contains("terminate called without an active exception") {
        ("(no exception: std::terminate called directly)".to_string(), None)
    } else {
        return None;
    };
    Some((ty, what))
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
    /// The system's frames it waits in, above its own (`syscall < poll_read`, `read`), for
    /// people: a hang is signed by the host's own code ([`HangStack::site`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waits_in: Option<String>,
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
pub fn faulthandler_frames(dump: &str) -> Option<(String, Option<String>)> {
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
/// them, for the first thread listed: the host's own frames first, with the system frames it
/// waits in (the system's: libc's `read`, `syscall`, Boost.Asio's `poll_read`, the
/// sanitizer's interceptors).
pub fn native_frames(text: &str) -> Option<(String, Option<String>)> {
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
        let rest = rest.trim_start().split_once(char::is_whitespace).map_or("", |(_, r)| r).trim_start();
        let rest = match rest.split_once(char::is_whitespace) {
            Some((addr, r)) if addr.starts_with("0x") => r.trim_start(),
            _ if rest.starts_with("0x") => "",
            _ => rest,
        };
        let rest = rest.strip_prefix("in ").unwrap_or(rest);
        // gdb: `FUNC (ARGS) at FILE:LINE` (no module) or `FUNC (ARGS) from MODULE`; eu-stack:
        // `FUNC - MODULE`.
        let (func, module) = if let Some((f, m)) = rest.rsplit_once(" - ") {
            (function_name(f), Some(m.trim()))
        } else {
            let (f, module) = match rest.rsplit_once(" at ") {
                Some((f, _)) => (f, None),
                None => rest.rsplit_once(" from ").map_or((rest, None), |(f, m)| (f, Some(m.trim()))),
            };
            let f = f.trim();
            // The arguments gdb prints after the function (`(fd=3, buf=0x7ff "")`).
            let f = match matching_open(f) {
                Some(open) if f.ends_with(')') && open > 0 => &f[..open],
                _ => f,
            };
            (function_name(f), module)
        };
        if func.is_empty() || func == "??" {
            continue;
        }
        let system = system_frame(&func, module);
        all.push((func, system));
    }
    own_first(all)
}

/// The host's own frames (the innermost [`TOP_FRAMES`], `read_line < main`), or every frame
/// when none is its own; with the system frames innermost before its first own frame, where
/// it waits (the [`TOP_FRAMES`] nearest the host's code, `syscall < poll_read`).
fn own_first(all: Vec<(String, bool)>) -> Option<(String, Option<String>)> {
    if all.is_empty() {
        return None;
    }
    let Some(first_own) = all.iter().position(|(_, lib)| !lib) else {
        let frames = all.iter().take(TOP_FRAMES).map(|(f, _)| f.as_str()).collect::<Vec<_>>().join(" < ");
        return Some((frames, None));
    };
    let waits: Vec<&str> = all[..first_own].iter().map(|(f, _)| f.as_str()).collect();
    let waits_in = (!waits.is_empty()).then(|| waits[waits.len().saturating_sub(TOP_FRAMES)..].join(" < "));
    let own: Vec<&str> = all.iter().filter(|(_, lib)| !lib).map(|(f, _)| f.as_str()).take(TOP_FRAMES).collect();
    Some((own.join(" < "), waits_in))
}

/// Samples the stack of a stopped-in-place native process with `gdb -batch` or, failing that,
/// `eu-stack` (each when installed; each given 10 s). `None` when neither is there, the
/// process cannot be traced, or no frame could be read.
///
/// A host with a thread on the CPU (a parser whose loop makes no progress, while the caller
/// waits for it without a deadline) is hung in that thread: the stack is that thread's, and the
/// thread that waits (the main one) is named in `by`, for the message.
pub fn sample_native(pid: i32) -> Option<HangStack> {
    let busy = busy_thread(pid, BUSY_WINDOW);
    let bt = if busy.is_some() { "thread apply all bt" } else { "bt" };
    // gdb first: it demangles Rust's v0 symbols (`_RNv…`), which eu-stack prints raw.
    let tools: [(&str, Vec<String>); 2] = [
        ("gdb", vec!["-batch".into(), "-nx".into(), "-p".into(), pid.to_string(), "-ex".into(), bt.into()]),
        ("eu-stack", vec!["-m".into(), "-p".into(), pid.to_string()]),
    ];
    for (tool, args) in tools {
        let Some(out) = run_bounded(tool, &args, std::time::Duration::from_secs(10)) else { continue };
        if let Some(tid) = busy
            && let Some((frames, waits_in)) = thread_section(&out, tid).and_then(|t| native_frames(&t))
        {
            let waiting = (tid != pid)
                .then(|| thread_section(&out, pid).and_then(|t| native_frames(&t)))
                .flatten()
                .map(|(f, w)| match w {
                    Some(w) => format!("; the main thread waits in {f}, in {w}"),
                    None => format!("; the main thread waits in {f}"),
                })
                .unwrap_or_default();
            let by = format!("{tool}: thread {tid} was on the CPU, a loop that makes no progress{waiting}");
            return Some(HangStack { by, frames, waits_in, blocked_in: None });
        }
        if let Some((frames, waits_in)) = native_frames(&out) {
            return Some(HangStack { by: tool.to_string(), frames, waits_in, blocked_in: None });
        }
    }
    None
}

/// How long a hung host's threads are watched for one on the CPU.
const BUSY_WINDOW: std::time::Duration = std::time::Duration::from_millis(300);

/// The thread of `pid` that wanted the CPU most while it was watched for `window`: its id, when
/// it was running or waiting for a CPU (state `R`) at two thirds of the looks at least, or ran
/// for a third of the window. A loop that makes no progress is runnable however busy the
/// machine is (on a loaded one it may get little CPU: counting CPU time alone missed it under
/// load); a host that waits sleeps in a call (state `S`), and uses next to none.
fn busy_thread(pid: i32, window: std::time::Duration) -> Option<i32> {
    // Each thread: its state letter and its CPU time (utime + stime, USER_HZ ticks).
    let look = || -> Option<std::collections::BTreeMap<i32, (char, u64)>> {
        let mut m = std::collections::BTreeMap::new();
        for t in std::fs::read_dir(format!("/proc/{pid}/task")).ok()?.flatten() {
            let Some(tid) = t.file_name().to_str().and_then(|n| n.parse::<i32>().ok()) else { continue };
            let stat = std::fs::read_to_string(t.path().join("stat")).unwrap_or_default();
            // After the name: the state, then (11th and 12th after it) utime and stime.
            let f: Vec<&str> = stat.rsplit_once(')').map(|(_, r)| r.split_whitespace().collect()).unwrap_or_default();
            let ticks = |i: usize| f.get(i).and_then(|x| x.parse::<u64>().ok()).unwrap_or(0);
            let state = f.first().and_then(|s| s.chars().next()).unwrap_or('?');
            m.insert(tid, (state, ticks(11) + ticks(12)));
        }
        Some(m)
    };
    const LOOKS: u32 = 30;
    let before = look()?;
    let mut runnable: std::collections::BTreeMap<i32, u32> = std::collections::BTreeMap::new();
    let mut after = before.clone();
    for _ in 0..LOOKS {
        std::thread::sleep(window / LOOKS);
        let Some(now) = look() else { break };
        for (t, (state, _)) in &now {
            if *state == 'R' {
                *runnable.entry(*t).or_default() += 1;
            }
        }
        after = now;
    }
    // /proc counts CPU time in USER_HZ, 100 a second on Linux whatever the kernel's own tick.
    let per_second = 100.0;
    let ran = |t: &i32| after.get(t).zip(before.get(t)).map_or(0, |(a, b)| a.1.saturating_sub(b.1));
    let (tid, looks, used) = after
        .keys()
        .map(|t| (*t, runnable.get(t).copied().unwrap_or(0), ran(t)))
        .max_by_key(|(t, looks, used)| (*looks, *used, std::cmp::Reverse(*t)))?;
    (looks * 3 >= LOOKS * 2 || used as f64 >= window.as_secs_f64() * per_second / 3.0).then_some(tid)
}

/// The lines of one thread's stack in a stack tool's text of every thread (`Thread 2 (Thread
/// 0x7f... (LWP 1235) ...):` from gdb, `TID 1235:` from eu-stack), its header first.
fn thread_section(text: &str, tid: i32) -> Option<String> {
    let lwp = format!("(LWP {tid})");
    let eu = format!("TID {tid}:");
    let header = |l: &str| l.starts_with("Thread ") || l.starts_with("TID ");
    let mut lines = text.lines().map(str::trim);
    lines.find(|l| header(l) && (l.contains(&lwp) || *l == eu))?;
    let body: Vec<&str> = lines.take_while(|l| !header(l)).collect();
    Some(format!("Thread {tid}\n{}", body.join("\n")))
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

    /// What AddressSanitizer (gcc 12's) printed for `host_mutants/c_sscanf_two.c`: a heap word
    /// overflowed through `sscanf`, the report's first frames the sanitizer's interceptor.
    const SSCANF_HEAP: &str = "==20480==ERROR: AddressSanitizer: heap-buffer-overflow on address 0x602000000018 at pc 0x7fc748c716c5 bp 0x7fff5152bdc0 sp 0x7fff5152b570\nWRITE of size 257 at 0x602000000018 thread T0\n    #0 0x7fc748c716c4 in scanf_common ../../../../src/libsanitizer/sanitizer_common/sanitizer_common_interceptors_format.inc:342\n    #1 0x7fc748c7230e in __interceptor___isoc99_vsscanf ../../../../src/libsanitizer/sanitizer_common/sanitizer_common_interceptors.inc:1531\n    #2 0x7fc748c723fe in __interceptor___isoc99_sscanf ../../../../src/libsanitizer/sanitizer_common/sanitizer_common_interceptors.inc:1554\n    #3 0x558dee848ad6 in hand_get /work/harness/tests/host_mutants/c_sscanf_two.c:39\n    #4 0x558dee848c14 in main /work/harness/tests/host_mutants/c_sscanf_two.c:50\n    #5 0x7fc748a45249 in __libc_start_call_main ../sysdeps/nptl/libc_start_call_main.h:58\n    #6 0x7fc748a45304 in __libc_start_main_impl ../csu/libc-start.c:360\n    #7 0x558dee848240 in _start (/tmp/h30/c_sscanf_two+0x2240)\n\n0x602000000018 is located 0 bytes to the right of 8-byte region [0x602000000010,0x602000000018)\nallocated by thread T0 here:\n    #0 0x7fc748cb89cf in __interceptor_malloc ../../../../src/libsanitizer/asan/asan_malloc_linux.cpp:69\n    #1 0x558dee848a97 in hand_get /work/harness/tests/host_mutants/c_sscanf_two.c:37\n";

    /// A stack word overflowed through `sscanf`: the default (slow) unwinder crashed on the
    /// smashed stack, and the report has no frame.
    const SSCANF_STACK_NO_FRAMES: &str = "AddressSanitizer:DEADLYSIGNAL\nAddressSanitizer: nested bug in the same thread, aborting.\n\n--- sanitizer log asan.20561 ---\n=================================================================\n==20561==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7ffeb3e60ed8 at pc 0x7f4d428716c5 bp 0x7ffeb3e60d40 sp 0x7ffeb3e604f0\nWRITE of size 1025 at 0x7ffeb3e60ed8 thread T0\n";

    /// The same schedule run again with the fast unwinder: the frame that called `sscanf` is
    /// skipped (the interceptor keeps no frame pointer), and the report goes on to name the
    /// function whose variable overflowed.
    const SSCANF_STACK_FAST: &str = "==12669==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7ffc11994e18 at pc 0x7f9f12a716c5 bp 0x7ffc11994c80 sp 0x7ffc11994430\nWRITE of size 9 at 0x7ffc11994e18 thread T0\n    #0 0x7f9f12a716c4 in scanf_common ../../../../src/libsanitizer/sanitizer_common/sanitizer_common_interceptors_format.inc:342\n    #1 0x7f9f12a7230e in __interceptor___isoc99_vsscanf ../../../../src/libsanitizer/sanitizer_common/sanitizer_common_interceptors.inc:1531\n    #2 0x55f4e8e78bac in main /work/harness/tests/host_mutants/c_sscanf_word.c:35\n    #3 0x7f9f12845249 in __libc_start_call_main ../sysdeps/nptl/libc_start_call_main.h:58\n\nAddress 0x7ffc11994e18 is located in stack of thread T0 at offset 40 in frame\n    #0 0x55f4e8e788e2 in first_word /work/harness/tests/host_mutants/c_sscanf_word.c:21\n\n  This frame has 1 object(s):\n    [32, 40) 'word' (line 22) <== Memory access at offset 40 overflows this variable\n";

    /// An overflow through `sscanf` is signed by the host's function that called it (the
    /// interceptor, `scanf_common`, in the message), never by the interceptor; a report whose
    /// unwinder crashed has its site from a second run's report (by the function whose
    /// variable overflowed), else `?`, and says it printed no frame.
    #[test]
    fn an_overflow_through_sscanf_is_signed_by_the_hosts_function() {
        let heap = crash_report(SSCANF_HEAP).unwrap();
        assert_eq!(heap.signature, "asan heap-buffer-overflow in hand_get");
        assert!(
            heap.headline.ends_with(
                "(in hand_get, through scanf_common < __interceptor___isoc99_vsscanf < __interceptor___isoc99_sscanf, called from main)"
            ),
            "{}",
            heap.headline
        );
        // Another function overflowing through the same sscanf is another finding.
        let other = SSCANF_HEAP.replace("in hand_get /work", "in hand_pget /work");
        assert_eq!(crash_report(&other).unwrap().signature, "asan heap-buffer-overflow in hand_pget");
        assert_eq!(asan_without_frames(SSCANF_HEAP), None);
        assert_eq!(asan_without_frames(SSCANF_STACK_NO_FRAMES).as_deref(), Some("stack-buffer-overflow"));
        let alone = crash_report(SSCANF_STACK_NO_FRAMES).unwrap();
        assert_eq!(alone.signature, "asan stack-buffer-overflow in ?");
        assert!(alone.headline.ends_with("(the sanitizer printed no frame)"), "{}", alone.headline);
        let completed = format!("{SSCANF_STACK_NO_FRAMES}\n{ASAN_SECOND_RUN}\n{SSCANF_STACK_FAST}");
        assert_eq!(asan_without_frames(&completed), None, "completed once");
        let r = crash_report(&completed).unwrap();
        assert_eq!(r.signature, "asan stack-buffer-overflow in first_word");
        assert!(r.headline.contains("through scanf_common < __interceptor___isoc99_vsscanf"), "{}", r.headline);
        assert!(r.headline.contains("from a second run of the same schedule"), "{}", r.headline);
        // A report that names only the system's frames (an overflow that ran off the stack's
        // end inside libc's scanf) is completed the same way.
        let off_the_end = "==11557==ERROR: AddressSanitizer: stack-overflow on address 0x7ffc71608000 (pc 0x7f219327f746 bp 0x7ffc71606fb0 sp 0x7ffc716068c0 T0)\n    #0 0x7f219327f746 in __vfscanf_internal ../stdio-common/vfscanf-internal.c:1140\n    #1 0x7f2193280361 in __isoc99_vsscanf ../libio/iovsscanf.c:32\n    #2 0x7f219347230e in __interceptor___isoc99_vsscanf ../../../../src/libsanitizer/sanitizer_common/sanitizer_common_interceptors.inc:1531\n";
        assert_eq!(asan_without_frames(off_the_end).as_deref(), Some("stack-overflow"));
        let completed = format!("{off_the_end}\n{ASAN_SECOND_RUN}\n{SSCANF_STACK_FAST}");
        assert_eq!(crash_report(&completed).unwrap().signature, "asan stack-buffer-overflow in first_word");
        // A report of the first run with its frames (the slow unwinder did not crash) is signed
        // by its first own frame, as ever.
        assert_eq!(crash_report(SSCANF_STACK_FAST).unwrap().signature, "asan stack-buffer-overflow in main");
    }

    /// A host's own code is the host's wherever it was built: in a folder named as glibc's
    /// (`csu/`, `libio/`, `nptl/`, `sysdeps/`) or a library's (`boost/`), its frames are its
    /// own (they were taken for the system's by their source path, and such a host was signed
    /// `in ?` or `in scanf_common`); the system's frames are told by the object file they come
    /// from or by their function, whatever folder names their source.
    #[test]
    fn frames_are_the_systems_by_their_object_file_not_by_their_source_folder() {
        for folder in ["/home/u/csu/", "/src/libio/", "/w/nptl/", "/w/sysdeps/", "/w/boost/", "/usr/include/x/"] {
            let heap = SSCANF_HEAP.replace("/work/harness/tests/host_mutants/", folder);
            let r = crash_report(&heap).unwrap();
            assert_eq!(r.signature, "asan heap-buffer-overflow in hand_get", "{folder}");
            assert!(r.headline.ends_with("called from main)"), "{folder}: {}", r.headline);
            let fast = SSCANF_STACK_FAST.replace("/work/harness/tests/host_mutants/", folder);
            let completed = format!("{SSCANF_STACK_NO_FRAMES}\n{ASAN_SECOND_RUN}\n{fast}");
            assert_eq!(
                crash_report(&completed).unwrap().signature,
                "asan stack-buffer-overflow in first_word",
                "{folder}"
            );
            let eu = format!(
                "TID 1:\n#0  0x7f3 __GI___libc_read - /usr/lib/x86_64-linux-gnu/libc.so.6\n#1  0x555 read_line - {folder}c_host\n#2  0x556 main - {folder}c_host\n"
            );
            assert_eq!(native_frames(&eu).unwrap().0, "read_line < main", "{folder}");
            let gdb = format!(
                "#0  0x00007f in __GI___libc_read (fd=3) at ../sysdeps/read.c:26\n#1  0x000055 in read_line (fd=3) at {folder}host.c:20\n#2  0x000055 in main () at {folder}host.c:40\n"
            );
            assert_eq!(native_frames(&gdb).unwrap().0, "read_line < main", "{folder}");
        }
        // The system's code is the system's by its object file, whatever its function's name.
        let libc =
            "#0 0x7f in vfscanf_helper (/lib/x86_64-linux-gnu/libc.so.6+0x5e)\n#1 0x55 in parse /h/csu/host.c:9\n";
        let report = format!(
            "==1==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7f\nWRITE of size 9\n    {}",
            libc.replace('\n', "\n    ")
        );
        assert_eq!(crash_report(&report).unwrap().signature, "asan stack-buffer-overflow in parse");
        // A source file named without a folder is a source file, not a part of the function.
        let bare = "==1==ERROR: AddressSanitizer: stack-buffer-overflow on address 0x7f\nWRITE of size 9\n    #0 0x55 in read_line host.c:20\n    #1 0x56 in main host.c:40\n";
        assert_eq!(crash_report(bare).unwrap().signature, "asan stack-buffer-overflow in read_line");
    }

    /// gdb's stack of `host_mutants/cpp_uncaught_hangup.cpp` at its SIGABRT (a second run).
    const TERMINATE_GDB: &str = "Program received signal SIGABRT, Aborted.\n#0  __pthread_kill_implementation (threadid=<optimized out>, signo=signo@entry=6, no_tid=no_tid@entry=0) at ./nptl/pthread_kill.c:44\n#1  0x00007ffff7aa8f4f in __pthread_kill_internal (signo=6, threadid=<optimized out>) at ./nptl/pthread_kill.c:78\n#2  0x00007ffff7a59fb2 in __GI_raise (sig=sig@entry=6) at ../sysdeps/posix/raise.c:26\n#3  0x00007ffff7a44472 in __GI_abort () at ./stdlib/abort.c:79\n#4  0x00007ffff7c9d919 in ?? () from /lib/x86_64-linux-gnu/libstdc++.so.6\n#5  0x00007ffff7ca8e1a in ?? () from /lib/x86_64-linux-gnu/libstdc++.so.6\n#6  0x00007ffff7ca8e85 in std::terminate() () from /lib/x86_64-linux-gnu/libstdc++.so.6\n#7  0x00007ffff7ca90d8 in __cxa_throw () from /lib/x86_64-linux-gnu/libstdc++.so.6\n#8  0x0000555555555215 in Port::check (r=-1, what=0x55555555a004 \"read\") at cpp_uncaught_hangup.cpp:60\n#9  0x0000555555555243 in Port::read_answer[abi:cxx11]() (this=0x7fffffffe3d0) at cpp_uncaught_hangup.cpp:51\n#10 0x000055555555524f in main (argc=2, argv=0x7fffffffe4f8) at cpp_uncaught_hangup.cpp:75\n";

    /// libstdc++'s words about an exception nobody caught are read into the signature: what
    /// was thrown and, with the stack at the abort, the host's frame that threw (`what()`,
    /// whose text varies, in the message); libc++'s words too.
    /// With gdb installed but no second run that threw the same, the message says so; it said
    /// `no stack, gdb took none`, as if gdb were missing (issue 38, "What was seen" 6).
    #[test]
    fn an_uncaught_exception_without_a_stack_says_why() {
        let said = "terminate called after throwing an instance of 'std::future_error'\n  what():  std::future_error: Broken promise\n";
        let why = format!("{said}\n{ABORT_NO_STACK}4 second runs under gdb did not throw it again\n");
        let r = crash_report(&why).unwrap();
        assert!(
            r.headline.ends_with("(where it was thrown: not known, 4 second runs under gdb did not throw it again)"),
            "{}",
            r.headline
        );
        assert_eq!(r.signature, "uncaught C++ exception std::future_error");
    }

    /// A stack from a second run that threw the same type with another what() is said to be
    /// that run's, with what it threw.
    #[test]
    fn a_stack_from_a_second_run_that_threw_otherwise_says_so() {
        let said = "terminate called after throwing an instance of 'std::system_error'\n  what():  write: Input/output error\n";
        let s = format!("{said}\n{ABORT_STACK}\n{TERMINATE_GDB}\n{ABORT_OTHER}read: Input/output error\n");
        let r = crash_report(&s).unwrap();
        assert_eq!(r.signature, "uncaught C++ exception std::system_error in Port::check");
        assert!(
            r.headline.ends_with(
                "(thrown in Port::check, called from Port::read_answer, in a second run that threw it with what(): read: Input/output error)"
            ),
            "{}",
            r.headline
        );
    }

    #[test]
    fn an_uncaught_cpp_exception_is_signed_by_what_was_thrown_and_where() {
        let said = "terminate called after throwing an instance of 'boost::wrapexcept<boost::system::system_error>'\n  what():  write: Input/output error\n";
        let alone = crash_report(said).unwrap();
        assert_eq!(alone.kind, "c++");
        assert_eq!(alone.signature, "uncaught C++ exception boost::wrapexcept<boost::system::system_error>");
        assert!(alone.headline.contains("what(): write: Input/output error"), "{}", alone.headline);
        let with_stack = format!("{said}\n{ABORT_STACK}\n{TERMINATE_GDB}");
        let r = crash_report(&with_stack).unwrap();
        assert_eq!(r.signature, "uncaught C++ exception boost::wrapexcept<boost::system::system_error> in Port::check");
        assert!(r.headline.ends_with("(thrown in Port::check, called from Port::read_answer)"), "{}", r.headline);
        let llvm = "libc++abi: terminating due to uncaught exception of type std::runtime_error: no prompt\n";
        assert_eq!(crash_report(llvm).unwrap().signature, "uncaught C++ exception std::runtime_error");
        assert!(uncaught_exception(said) && !uncaught_exception("all fine\n"));
    }

    /// A hang is named by the innermost frame of the host's own code: the system's frames it
    /// waits in (libc's `syscall` as gdb prints it with libc's sources, Boost.Asio's header
    /// code, libstdc++'s) go in the message, whichever tool took the stack.
    #[test]
    fn a_template_frame_is_named_without_its_template_arguments() {
        assert_eq!(
            function_name(
                "boost::asio::detail::reactive_socket_recv_op<boost::asio::mutable_buffers_1, \
                 boost::asio::detail::read_op<boost::asio::basic_serial_port<boost::asio::any_io_executor>, \
                 std::vector<char, std::allocator<char> > > >::do_complete(void*, int)"
            ),
            "boost::asio::detail::reactive_socket_recv_op<…>::do_complete"
        );
        assert_eq!(function_name("std::vector<int>::operator[](unsigned long)"), "std::vector<…>::operator[]");
        assert_eq!(function_name("Port::operator<<(char const*)"), "Port::operator<<");
        assert_eq!(function_name("operator<(Pos const&, Pos const&)"), "operator<");
        assert_eq!(function_name("Ptr<int>::operator->()"), "Ptr<…>::operator->");
        assert_eq!(function_name("read_line"), "read_line");
    }

    /// One thread's stack out of gdb's `thread apply all bt` or eu-stack's listing.
    #[test]
    fn one_threads_stack_is_cut_out_of_every_threads() {
        let gdb = "Thread 2 (Thread 0x7f00 (LWP 1235) \"host\"):\n#0  0x0000 in parse_values (a=0x1) at h.c:20\n\
                   #1  0x0000 in parser (arg=0x0) at h.c:50\n\n\
                   Thread 1 (Thread 0x7f01 (LWP 1234) \"host\"):\n#0  0x0000 in __futex_wait () from /lib/libc.so.6\n\
                   #1  0x0000 in command (line=0x1) at h.c:70\n#2  0x0000 in main () at h.c:80\n";
        let busy = thread_section(gdb, 1235).and_then(|t| native_frames(&t)).unwrap();
        assert_eq!(busy.0, "parse_values < parser");
        let main = thread_section(gdb, 1234).and_then(|t| native_frames(&t)).unwrap();
        assert_eq!(main.0, "command < main");
        assert_eq!(thread_section(gdb, 99), None);
        let eu = "PID 1234 - process\nTID 1234:\n#0  0x7f in __futex_wait - /lib/libc.so.6\n#1  0x55 in command - /h\n\
                  TID 1235:\n#0  0x55 in parse_values - /h\n";
        assert_eq!(thread_section(eu, 1235).and_then(|t| native_frames(&t)).unwrap().0, "parse_values");
    }

    #[test]
    fn a_hang_under_system_libraries_is_named_by_the_hosts_frame() {
        let gdb = "#0  syscall () at ../sysdeps/unix/sysv/linux/x86_64/syscall.S:38\n#1  0x000055 in boost::asio::detail::descriptor_ops::poll_read (d=3, state=0 '\\000', msec=-1, ec=...) at /usr/include/boost/asio/detail/impl/descriptor_ops.ipp:450\n#2  0x000055 in boost::asio::detail::descriptor_ops::sync_read (d=3, state=0 '\\000', bufs=0x7ff, count=1, all_empty=false, ec=...) at /usr/include/boost/asio/detail/impl/descriptor_ops.ipp:160\n#3  0x000055 in BarrettHand::initialize (this=0x7ffd) at src/hand.cpp:88\n#4  0x000055 in main () at src/main.cpp:12\n";
        let (frames, waits) = native_frames(gdb).unwrap();
        assert_eq!(frames, "BarrettHand::initialize < main");
        assert_eq!(
            waits.as_deref(),
            Some(
                "syscall < boost::asio::detail::descriptor_ops::poll_read < boost::asio::detail::descriptor_ops::sync_read"
            )
        );
        let ros = "TID 9:\n#0  0x00007f poll - /usr/lib/x86_64-linux-gnu/libc.so.6\n#1  0x00007f boost::asio::detail::descriptor_ops::poll_read(int, unsigned char, int, boost::system::error_code&) - /opt/ros/noetic/lib/libserial.so\n#2  0x000055 BhandNode::read_reply(std::string&) - /ws/devel/lib/bhand/bhand_node\n#3  0x000055 main - /ws/devel/lib/bhand/bhand_node\n";
        let stack = HangStack {
            by: "eu-stack".into(),
            frames: native_frames(ros).unwrap().0,
            waits_in: native_frames(ros).unwrap().1,
            blocked_in: None,
        };
        assert_eq!(stack.site(), "BhandNode::read_reply");
        assert_eq!(stack.waits_in.as_deref(), Some("poll < boost::asio::detail::descriptor_ops::poll_read"));
        // A host's own shared library is the host's (not the system's).
        let own_lib = "#0 0x7f in read () from /lib/x86_64-linux-gnu/libc.so.6\n#1 0x7f in HandGet () from /usr/local/lib/libbarrett.so\n";
        assert_eq!(native_frames(own_lib).unwrap().0, "HandGet");
    }

    /// A thread spinning on `strstr` (handif.c's worker, waiting for a prompt a garbled byte
    /// broke), as gdb with libc's sources prints it: the intrinsic inlined into libc's
    /// `__strstr_avx512` is a frame of its own, and the thread starts in libc's `start_thread`.
    /// Neither is the host's code: the hang is signed by the host's loop.
    #[test]
    fn intrinsics_inlined_in_libc_and_libcs_thread_start_are_the_systems_frames() {
        let gdb = "Thread 2 (Thread 0x7fe77680b6c0 (LWP 28811) \"spin\"):\n\
#0  _mm512_mask_testn_epi8_mask (__B=..., __A=..., __U=1152921504606846975) at /usr/lib/gcc/x86_64-linux-gnu/12/include/avx512bwintrin.h:1861\n\
#1  __strstr_avx512 (haystack=0x55aa0c525060 <buf> 'x' <repeats 200 times>..., ned=0x55aa0c523004 \"=>\") at ../sysdeps/x86_64/multiarch/strstr-avx512.c:112\n\
#2  0x000055aa0c5221a0 in processCommands (vhand=0x0) at handif/handif.c:140\n\
#3  0x00007fe7768981f5 in start_thread (arg=<optimized out>) at ./nptl/pthread_create.c:442\n\
#4  0x00007fe7769188ec in clone3 () at ../sysdeps/unix/sysv/linux/x86_64/clone3.S:81\n";
        assert_eq!(
            native_frames(gdb).unwrap(),
            ("processCommands".into(), Some("_mm512_mask_testn_epi8_mask < __strstr_avx512".into()))
        );
    }

    #[test]
    fn hang_stacks_name_the_hosts_own_code() {
        let py = "Fatal Python error: Aborted\n\nCurrent thread 0x00007f (most recent call first):\n  File \"/usr/lib/python3/dist-packages/serial/serialposix.py\", line 565 in read\n  File \"/t/hosts/py_host.py\", line 20 in read_prompt\n  File \"/t/hosts/py_host.py\", line 40 in main\n  File \"/t/hosts/py_host.py\", line 44 in <module>\n\nExtension modules: x\n";
        assert_eq!(
            faulthandler_frames(py).unwrap(),
            (
                "py_host.py:read_prompt < py_host.py:main < py_host.py:<module>".into(),
                Some("serialposix.py:read".into())
            )
        );
        let eu = "PID 12 - process\nTID 12:\n#0  0x00007f3 __GI___libc_read - /usr/lib/x86_64-linux-gnu/libc.so.6\n#1  0x0000555 read_line - /tmp/c_host\n#2  0x0000556 main - /tmp/c_host\n#3  0x00007f4 __libc_start_call_main - /usr/lib/x86_64-linux-gnu/libc.so.6\n";
        assert_eq!(native_frames(eu).unwrap(), ("read_line < main".into(), Some("__GI___libc_read".into())));
        let gdb = "0x00007f in __GI___libc_read (fd=3, buf=0x7ff, nbytes=1) at ../sysdeps/unix/sysv/linux/read.c:26\n#0  0x00007f in __GI___libc_read (fd=3) at ../sysdeps/read.c:26\n#1  0x000055 in read_line (fd=3, buf=0x7ff \"\") at host.c:20\n#2  0x000055 in main () at host.c:40\n";
        assert_eq!(native_frames(gdb).unwrap().0, "read_line < main");
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
            frames: faulthandler_frames(d).unwrap().0,
            waits_in: None,
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

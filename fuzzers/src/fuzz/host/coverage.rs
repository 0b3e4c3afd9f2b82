//! The host's own code coverage, read through AFL++'s instrumentation protocol (issue 42).
//!
//! A host built as fuzzing users already build it writes its edge hits to a SysV shared-memory
//! map named by `__AFL_SHM_ID`: C and C++ built with `afl-cc` / `afl-clang-fast` (run without
//! AFL's fork server, such a binary finds no fork server to talk to and just runs), Python
//! through `python-afl` (`afl.init()`, which hashes the lines it runs into the same map) or the
//! wheel's `gcl.afl_cov` (`python -m gcl.afl_cov host.py`: the same without python-afl), Rust
//! built with `cargo-afl` (the same runtime as `afl-cc`; `hosts/rust_host` in the harness's tests). For each run [`super::Slots`] makes a map ([`ShmMap`]), gives its id
//! to the host, and reads the edges hit (the map's non-zero bytes) after the run; the campaign
//! keeps their union and the schedules that reached an edge no run before them reached
//! ([`Coverage`]).
//!
//! No segment outlives the run, nor `gcl`: the map is marked for removal as soon as `gcl` has
//! attached it (Linux keeps a segment so marked until its last process detaches, and still lets
//! a process attach it by id), so a `gcl` killed by SIGKILL leaks nothing either.
//!
//! A host that wrote no edge in its run without misbehaviour is not instrumented (or not so that
//! it writes this map): the campaign says so ([`NOT_INSTRUMENTED`]) and is guided by wire paths
//! alone, as without `--coverage`. The share of the host's edges reached needs the host's edge
//! count: an `afl-cc` binary prints its map size and exits when run with `AFL_DUMP_MAP_SIZE=1`
//! ([`instrumented_edges`]); python-afl's map is a hash of lines, whose count it does not know.
//!
//! Guidance by coverage ([`Coverage::pick`]) chooses the kept schedule to mutate by a power
//! schedule in the manner of AFLFast: an entry's energy grows with the rarity of the rarest edge
//! it reached (how few kept schedules reach it) and shrinks with how often it was chosen before.
//! Both are counted over the runs guidance may see, so a campaign repeats run for run.
//!
//! Minimization keeps a finding's coverage: the edges its run was the first of the campaign to
//! reach (what [`Coverage::take`] returns) must be reached by the smaller schedule's run too
//! (`super::minimize`).

#![allow(unsafe_code)] // SysV shared memory: shmget, shmat, shmdt and shmctl have no safe wrapper

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use nix::libc;
use serde::{Deserialize, Serialize};

use crate::sim::misbehave::Schedule;

/// What a campaign does with the host's code coverage (`gcl fuzz host --coverage`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CoverageUse {
    /// No map: the host's coverage is not read.
    #[default]
    Off,
    /// Read and reported (edges over time), but wire paths alone guide: the same runs as
    /// `Off`, for comparing guidance with and without coverage at equal seeds.
    Measure,
    /// Read, reported, and guiding: a schedule that reached a new edge is kept and mutated.
    Guide,
}

impl CoverageUse {
    /// The name `--coverage` takes.
    pub fn name(self) -> &'static str {
        match self {
            CoverageUse::Off => "off",
            CoverageUse::Measure => "measure",
            CoverageUse::Guide => "guide",
        }
    }
}

impl std::str::FromStr for CoverageUse {
    type Err = String;
    fn from_str(s: &str) -> Result<CoverageUse, String> {
        match s {
            "off" => Ok(CoverageUse::Off),
            "measure" => Ok(CoverageUse::Measure),
            "guide" | "on" => Ok(CoverageUse::Guide),
            _ => Err(format!("`{s}`: --coverage is guide, measure or off")),
        }
    }
}

/// The environment variable an instrumented host reads its map's id from.
pub const SHM_ENV: &str = "__AFL_SHM_ID";

/// The environment variable that tells an `afl-cc` binary the map's size.
pub const MAP_SIZE_ENV: &str = "AFL_MAP_SIZE";

/// The map size AFL++ uses unless the host asks for more (python-afl's fixed size).
pub const MAP_SIZE: usize = 1 << 16;

/// The largest map `gcl` makes (AFL++'s own limit for a map given by `AFL_MAP_SIZE`).
pub const MAP_SIZE_MAX: usize = 1 << 23;

/// What the campaign says of a host that wrote no edge to its map.
pub const NOT_INSTRUMENTED: &str = "coverage: the host wrote no edge to the AFL map it was given (__AFL_SHM_ID): it \
is not built with afl-cc/afl-clang-fast, python-afl or cargo-afl, nor run through gcl.afl_cov; guided by wire paths only";

/// A SysV shared-memory map for one run, removed when dropped (and marked for removal from the
/// start: see the module's notes).
#[derive(Debug)]
pub struct ShmMap {
    id: i32,
    addr: *mut u8,
    size: usize,
}

impl ShmMap {
    /// A zeroed map of `size` bytes, attached, already marked for removal.
    pub fn new(size: usize) -> std::io::Result<ShmMap> {
        // SAFETY: shmget takes no pointer; a private key makes a new segment each call.
        let id = unsafe { libc::shmget(libc::IPC_PRIVATE, size, libc::IPC_CREAT | libc::IPC_EXCL | 0o600) };
        if id < 0 {
            return Err(std::io::Error::last_os_error());
        }
        // SAFETY: attaches the segment just made at an address the kernel chooses.
        let addr = unsafe { libc::shmat(id, std::ptr::null(), 0) };
        // SAFETY: marks the segment for removal; Linux removes it once the last process that
        // attached it detaches (gcl's map when dropped, or gcl's exit however it ends).
        let removed = unsafe { libc::shmctl(id, libc::IPC_RMID, std::ptr::null_mut()) };
        if addr as isize == -1 {
            let e = std::io::Error::last_os_error();
            return Err(e);
        }
        let map = ShmMap { id, addr: addr.cast(), size };
        if removed < 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok(map)
    }

    /// Its id, for `__AFL_SHM_ID`.
    pub fn id(&self) -> i32 {
        self.id
    }

    /// Its size in bytes.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The edges hit: the indices of the map's non-zero bytes, in order.
    pub fn edges(&self) -> Vec<u32> {
        // SAFETY: the map is `size` bytes attached for as long as `self` lives; the host that
        // wrote to it has ended (a process it left behind may still write: bytes, never UB
        // for u8 reads through a raw pointer, read one at a time).
        (0..self.size).filter(|&i| unsafe { self.addr.add(i).read_volatile() } != 0).map(|i| i as u32).collect()
    }
}

impl Drop for ShmMap {
    fn drop(&mut self) {
        // SAFETY: detaches the map attached in `new` (the segment was marked for removal there).
        unsafe {
            libc::shmdt(self.addr.cast());
        }
    }
}

/// How a campaign reads the host's coverage: the map size to make (and give in
/// `AFL_MAP_SIZE`), and the host's edge count when it could be learnt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MapRequest {
    /// The map's size in bytes.
    pub size: usize,
}

impl Default for MapRequest {
    fn default() -> MapRequest {
        MapRequest { size: MAP_SIZE }
    }
}

/// The program a command runs: its first word, found on `PATH` when it has no slash.
fn program_path(program: &str) -> Option<PathBuf> {
    if program.contains('/') {
        return Some(PathBuf::from(program));
    }
    std::env::var_os("PATH").and_then(|p| std::env::split_paths(&p).map(|d| d.join(program)).find(|c| c.is_file()))
}

/// Whether `path` is an executable built with AFL++'s instrumentation (it names `__AFL_SHM_ID`
/// and is an ELF file).
fn is_afl_binary(path: &Path) -> bool {
    let Ok(bytes) = std::fs::read(path) else { return false };
    bytes.starts_with(b"\x7fELF") && bytes.windows(SHM_ENV.len()).any(|w| w == SHM_ENV.as_bytes())
}

/// The host's instrumented edges, when its program is an `afl-cc` binary: the map size it
/// prints when run with `AFL_DUMP_MAP_SIZE=1` (it then exits without running), the edge count
/// plus AFL++'s reserved first slots. `None` for any other program (a Python host, a script, a
/// wrapper), or one that did not answer within a few seconds.
pub fn instrumented_edges(command: &[String]) -> Option<u64> {
    let path = program_path(command.first()?)?;
    if !is_afl_binary(&path) {
        return None;
    }
    let mut child = Command::new(&path)
        .env("AFL_DUMP_MAP_SIZE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(10)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
        }
    }
    let mut out = String::new();
    std::io::Read::read_to_string(&mut child.stdout.take()?, &mut out).ok()?;
    out.trim().parse::<u64>().ok().filter(|n| *n > 0)
}

/// The map size a host asks for: its edge count (from [`instrumented_edges`]) rounded up to a
/// power of two, at least [`MAP_SIZE`], at most [`MAP_SIZE_MAX`].
pub fn map_size_for(edges: Option<u64>) -> usize {
    let want = edges.map_or(MAP_SIZE, |e| (e as usize).next_power_of_two());
    want.clamp(MAP_SIZE, MAP_SIZE_MAX)
}

/// The map size a run's environment asks for (`AFL_MAP_SIZE`, set by the campaign from
/// [`map_size_for`]), else [`MAP_SIZE`].
pub fn map_size_in(env: &[(String, String)]) -> usize {
    env.iter()
        .find(|(k, _)| k == MAP_SIZE_ENV)
        .and_then(|(_, v)| v.parse::<usize>().ok())
        .map_or(MAP_SIZE, |n| n.clamp(MAP_SIZE, MAP_SIZE_MAX))
}

/// The map for one run that reads coverage as `coverage` says (`None` when off), its id put in
/// the run's environment `env` (`__AFL_SHM_ID`, replacing a former run's).
pub fn map_for(coverage: CoverageUse, env: &mut Vec<(String, String)>) -> std::io::Result<Option<ShmMap>> {
    if coverage == CoverageUse::Off {
        return Ok(None);
    }
    let map = ShmMap::new(map_size_in(env))?;
    env.retain(|(k, _)| k != SHM_ENV);
    env.push((SHM_ENV.to_string(), map.id().to_string()));
    Ok(Some(map))
}

/// A schedule for people: `silence@3 truncate@5`.
pub fn schedule_text(s: &Schedule) -> String {
    s.planned.iter().map(|p| format!("{}@{}", p.op, p.answer)).collect::<Vec<_>>().join(" ")
}

/// One point of the campaign's coverage over time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoveragePoint {
    /// Wall time since the campaign's start, milliseconds.
    pub ms: u64,
    /// Runs taken in by then.
    pub runs: u64,
    /// Edges reached by then.
    pub edges: u64,
}

/// A schedule that reached edges no earlier run had.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Added {
    /// The run.
    pub run: u64,
    /// The edges it added.
    pub new_edges: u64,
    /// Its schedule for people (`op@answer` items; `no misbehaviour` for run 0).
    pub schedule: String,
    /// Its schedule, to run again (`gcl check-host --serve --misbehave` or a bundle).
    pub planned: Schedule,
}

/// What a campaign learnt of the host's code coverage (`fuzz.json`'s `coverage`).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoverageAccount {
    /// Whether any run's map had an edge: the host is instrumented.
    pub instrumented: bool,
    /// Edges reached by the union of the runs.
    pub edges: u64,
    /// The host's instrumented edges (its map size, for an `afl-cc` binary), when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub host_edges: Option<u64>,
    /// The map size given to the host.
    pub map_size: u64,
    /// Schedules kept because they reached a new edge.
    pub kept: u64,
    /// Edges reached over time: a point whenever they rose, and the campaign's end.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub over_time: Vec<CoveragePoint>,
    /// The runs that added coverage (the first [`ADDED_KEPT`]), in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub added_by: Vec<Added>,
    /// Why coverage did not guide the campaign ([`NOT_INSTRUMENTED`]), when it did not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

impl CoverageAccount {
    /// The share of the host's edges reached, percent, when its edge count is known.
    pub fn share(&self) -> Option<f64> {
        self.host_edges.filter(|n| *n > 0).map(|n| 100.0 * self.edges as f64 / n as f64)
    }

    /// One line for people: `coverage: 41 edges of 57 (72%), 6 schedules kept for new edges`.
    pub fn line(&self) -> String {
        if let Some(n) = &self.note {
            return n.clone();
        }
        let of = match (self.host_edges, self.share()) {
            (Some(n), Some(p)) => format!(" of {n} ({p:.0}%)"),
            _ => String::new(),
        };
        format!("coverage: {} edges{of} reached, {} schedules kept for new edges", self.edges, self.kept)
    }
}

/// Most runs listed in [`CoverageAccount::added_by`].
pub const ADDED_KEPT: usize = 64;

/// A campaign's coverage as runs are taken in (in index order): the edges reached and by how
/// many runs, and each kept schedule's edges.
#[derive(Debug, Default)]
pub struct Coverage {
    /// Each edge reached, with the number of runs taken in that reached it.
    hits: BTreeMap<u32, u64>,
    /// The edges of the last [`RECENT`] runs taken in (index, edges): what a run scheduled
    /// before they were taken in does not see.
    recent: std::collections::VecDeque<(u64, Vec<u32>)>,
    /// Per corpus entry (same order as the campaign's corpus): its edges.
    entries: Vec<Vec<u32>>,
    account: CoverageAccount,
}

/// Runs whose edges [`Coverage`] keeps apart: more than `--jobs` (at most 64), the runs taken
/// in that a run being scheduled may not see.
const RECENT: usize = 64;

impl Coverage {
    /// Nothing reached yet; maps of `map_size` bytes for a host of `host_edges` edges.
    pub fn new(map_size: usize, host_edges: Option<u64>) -> Coverage {
        Coverage {
            account: CoverageAccount { map_size: map_size as u64, host_edges, ..Default::default() },
            ..Default::default()
        }
    }

    /// Takes in run `i`'s edges (`None`: no map was read), at `ms` since the start after
    /// `runs` runs, its schedule as `schedule`: the edges it reached that no earlier run had,
    /// in order (the run is then in `added_by`).
    pub fn take(&mut self, i: u64, edges: Option<&[u32]>, ms: u64, runs: u64, schedule: &Schedule) -> Vec<u32> {
        let Some(edges) = edges else { return Vec::new() };
        let mut first = Vec::new();
        for &e in edges {
            let n = self.hits.entry(e).or_default();
            if *n == 0 {
                first.push(e);
            }
            *n += 1;
        }
        let new = first.len() as u64;
        self.recent.push_back((i, edges.to_vec()));
        if self.recent.len() > RECENT {
            self.recent.pop_front();
        }
        if new > 0 {
            self.account.instrumented = true;
            self.account.edges = self.hits.len() as u64;
            self.account.over_time.push(CoveragePoint { ms, runs, edges: self.account.edges });
            if self.account.added_by.len() < ADDED_KEPT {
                let text = schedule_text(schedule);
                let text = if text.is_empty() { "no misbehaviour".to_string() } else { text };
                self.account.added_by.push(Added { run: i, new_edges: new, schedule: text, planned: schedule.clone() });
            }
        }
        first
    }

    /// A schedule kept in the corpus (at the corpus's next index), with its run's edges;
    /// `for_edges`: kept because they were new.
    pub fn kept(&mut self, edges: Option<&[u32]>, for_edges: bool) {
        self.entries.push(edges.map(<[u32]>::to_vec).unwrap_or_default());
        if for_edges {
            self.account.kept += 1;
        }
    }

    /// The edges of corpus entry `k`'s run (none when it read no map).
    pub fn entry_edges(&self, k: usize) -> &[u32] {
        self.entries.get(k).map_or(&[], Vec::as_slice)
    }

    /// Whether guidance by coverage is on: some run reached an edge.
    pub fn guiding(&self) -> bool {
        self.account.instrumented
    }

    /// The corpus entry (of the first `visible_entries`) to mutate for a run that sees runs
    /// `0..visible_runs`, drawn with `x` (a random number). Each entry weighs its energy: one
    /// over the number of visible runs that reached its rarest edge (AFLFast's inverse path
    /// frequency, by edge). An entry's mutations that keep what it did reach its edges too, so
    /// the energy of an entry falls as runs are made of it, and an entry that alone reached an
    /// edge gets most of the runs until they have tried it. An entry without edges weighs as
    /// one whose rarest edge every visible run reached.
    pub fn pick(&self, visible_entries: usize, visible_runs: u64, x: u64) -> usize {
        let n = visible_entries.min(self.entries.len());
        if n == 0 {
            return 0;
        }
        // The hits of the runs guidance sees: those taken in, less the recent ones it may not.
        let mut unseen: BTreeMap<u32, u64> = BTreeMap::new();
        for (_, edges) in self.recent.iter().filter(|(i, _)| *i >= visible_runs) {
            for e in edges {
                *unseen.entry(*e).or_default() += 1;
            }
        }
        let seen = |e: &u32| self.hits.get(e).map(|n| n - unseen.get(e).copied().unwrap_or(0));
        const SCALE: u64 = 1 << 24;
        let weights: Vec<u64> = (0..n)
            .map(|k| {
                let rarest = self.entries[k].iter().filter_map(seen).min().unwrap_or(visible_runs);
                (SCALE / rarest.max(1)).max(1)
            })
            .collect();
        let total: u64 = weights.iter().sum();
        let mut at = x % total.max(1);
        for (k, w) in weights.iter().enumerate() {
            if at < *w {
                return k;
            }
            at -= w;
        }
        n - 1
    }

    /// The account at the campaign's end (`ms`, after `runs` runs), with `note` when the host
    /// wrote no edge.
    pub fn account(&self, ms: u64, runs: u64) -> CoverageAccount {
        let mut a = self.account.clone();
        if !a.instrumented {
            a.note = Some(NOT_INSTRUMENTED.to_string());
        } else if a.over_time.last().is_none_or(|p| p.runs != runs) {
            a.over_time.push(CoveragePoint { ms, runs, edges: a.edges });
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::misbehave::{Operator, Planned};

    #[test]
    fn a_map_is_zeroed_gone_from_the_system_once_dropped_and_reads_what_was_written() {
        let map = ShmMap::new(MAP_SIZE).unwrap();
        assert!(map.edges().is_empty());
        // Another attachment by id, as the host makes: still possible though marked for removal.
        // SAFETY: attaches the map's segment by id; detached below.
        let other = unsafe { libc::shmat(map.id(), std::ptr::null(), 0) };
        assert_ne!(other as isize, -1, "a segment marked for removal can still be attached by id");
        // SAFETY: `other` is MAP_SIZE bytes attached just above.
        unsafe {
            let p: *mut u8 = other.cast();
            p.add(7).write_volatile(1);
            p.add(40_000).write_volatile(3);
            libc::shmdt(other);
        }
        assert_eq!(map.edges(), vec![7, 40_000]);
        let id = map.id();
        drop(map);
        // SAFETY: asks for the segment's status into a zeroed struct; fails once it is gone.
        let mut ds: libc::shmid_ds = unsafe { std::mem::zeroed() };
        let gone = unsafe { libc::shmctl(id, libc::IPC_STAT, &mut ds) };
        assert_eq!(gone, -1, "the segment is removed once its last attachment goes");
    }

    #[test]
    fn the_power_schedule_favours_the_entry_that_alone_reaches_an_edge_until_runs_have_tried_it() {
        let mut c = Coverage::new(MAP_SIZE, None);
        for (i, e) in [vec![1, 2], vec![1, 2, 3], vec![1, 2]].iter().enumerate() {
            c.take(i as u64, Some(e), 0, i as u64, &Schedule::default());
            c.kept(Some(e), true);
        }
        let picks = |c: &Coverage, runs: u64| {
            let mut n = [0u32; 3];
            for x in 0..3000u64 {
                n[c.pick(3, runs, x.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 7)] += 1;
            }
            n
        };
        let n = picks(&c, 3);
        assert!(n[1] > n[0] + n[2], "entry 1 alone reaches edge 3: {n:?}");
        // Runs made of it (reaching edge 3 again) take its energy down.
        for i in 3..20 {
            c.take(i, Some(&[1, 2, 3]), 0, i, &Schedule::default());
        }
        let tired = picks(&c, 20);
        assert!(tired[1] < tired[0] + tired[2], "17 runs reached edge 3 since: {tired:?} after {n:?}");
        // Runs guidance may not see yet do not count.
        assert_eq!(picks(&c, 3), n);
    }

    #[test]
    fn the_account_notes_a_host_that_wrote_no_edge_and_plots_the_rise() {
        let mut c = Coverage::new(MAP_SIZE, Some(20));
        assert!(c.take(0, Some(&[]), 5, 1, &Schedule::default()).is_empty());
        assert_eq!(c.account(9, 1).note.as_deref(), Some(NOT_INSTRUMENTED));
        let one = |op: Operator, answer: u32| Schedule { planned: vec![Planned { answer, op, arg: 0 }] };
        assert_eq!(c.take(1, Some(&[4, 5]), 10, 2, &one(Operator::Silence, 2)), vec![4, 5]);
        assert_eq!(c.take(2, Some(&[4, 6]), 20, 3, &one(Operator::Garbage, 1)), vec![6]);
        let a = c.account(30, 4);
        assert!(a.note.is_none());
        assert_eq!(a.edges, 3);
        assert_eq!(a.share(), Some(15.0));
        let edges: Vec<u64> = a.over_time.iter().map(|p| p.edges).collect();
        assert_eq!(edges, vec![2, 3, 3]);
        assert_eq!(a.line(), "coverage: 3 edges of 20 (15%) reached, 0 schedules kept for new edges");
        let by: Vec<(u64, u64, &str)> = a.added_by.iter().map(|x| (x.run, x.new_edges, x.schedule.as_str())).collect();
        assert_eq!(by, vec![(1, 2, "silence@2"), (2, 1, "garbage@1")]);
    }
}

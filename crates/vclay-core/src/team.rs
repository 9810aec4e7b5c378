//! A persistent team of threads for short phased programs, such as one time step of a
//! mid-sized simulation, where a scheduler's cost per parallel phase would exceed the work.
//!
//! # What
//! A *phased program* is a list of phases; phase `k` has `counts[k]` tasks, run as
//! `run(k, task)`. Every task of phase `k` starts after every task of the phases before it has
//! finished. [`run_phases`] runs a program on the global [`Team`]: the calling thread and up to
//! [`MAX_TEAM`] `- 1` helper threads.
//!
//! Two safe shared buffers let the tasks of a phase write disjoint parts of one slice:
//! [`SharedSlice`] hands out checked borrows of index ranges (a conflicting borrow panics, so a
//! wrongly phased program fails loudly instead of racing), and [`SharedSlice::read`] borrows the
//! whole slice for reading in a later phase.
//!
//! # How
//! Every thread walks the phases in order. At phase `k` it waits (spinning) until the count of
//! finished tasks reaches the number of tasks in the phases before `k`; then it claims and runs
//! the tasks it owns (task `t` belongs to the thread of rank `t % threads`, the caller being
//! rank 0), then any task of the phase still unclaimed. A claim tags the task's flag with the
//! program's epoch, so flags need no reset. A thread only waits at phase `k` after every task
//! of the earlier phases has been claimed by a thread that is running it, so the wait always
//! ends: the program completes even if the helpers never arrive, with the caller running every
//! task itself. Results therefore never depend on how many threads took part, provided that each
//! task writes only its own part.
//!
//! The owner rule keeps each thread on the same part of the data from phase to phase and from
//! program to program, in its own cache: with a shared ticket counter instead (tried first),
//! which thread took which task was left to chance, and a level-2 solid step spent about a
//! third more time in its map products reading lines the other core had written.
//!
//! Helpers spin for [`SPIN`] after their last program, so that a loop of steps finds them
//! awake, then park. A caller that finds the team busy (another thread's program, or a program
//! started from inside a task) runs its program alone, in order.
//!
//! The phase barrier is a release increment of the finished count and an acquire load of it.
//! Helpers register before they read a posted program and the caller waits for all of them to
//! leave before it returns, so no helper touches a program's borrowed data after
//! [`Team::run`] returns (the registration and the close are sequentially consistent, the
//! classic two-flag handshake).
//!
//! This module is the workspace's only `unsafe` code: raw pointers to the caller's program and
//! to the slices of [`SharedSlice`], each use with its safety argument.
#![allow(unsafe_code)]

use std::any::Any;
use std::marker::PhantomData;
use std::ops::{Deref, DerefMut, Range};
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Largest team (caller included). Phased programs are meant for work of tens of
/// microseconds per phase, where more threads mostly add barrier traffic.
pub const MAX_TEAM: usize = 4;

/// Most tasks of a program run by a team (larger programs run on the caller alone).
pub const MAX_TASKS: usize = 1024;

/// How long an idle helper spins for the next program before it parks.
pub const SPIN: Duration = Duration::from_micros(100);

/// The task function of a phased program: `run(phase, task)`.
pub type TaskFn<'a> = dyn Fn(usize, usize) + Sync + 'a;

/// A posted program, its lifetime erased (valid while the caller is inside [`Team::run`]).
#[derive(Clone, Copy)]
struct Job {
    counts: *const [usize],
    run: *const TaskFn<'static>,
}

// SAFETY: a `Job` only travels to helpers that dereference it while registered in
// `Shared::active`; `Team::run` keeps the pointees alive until no helper is registered.
unsafe impl Send for Job {}

/// A claim flag on a cache line of its own: the threads claim different tasks at the same
/// moment, and flags sharing a line would bounce it between their cores.
type Padded = crate::par::CacheAligned<AtomicUsize>;

struct Shared {
    /// Odd while a program is open; incremented to open and to close.
    epoch: AtomicUsize,
    job: Mutex<Option<Job>>,
    /// Per task (numbered through the program), the epoch of its last claim.
    claims: Box<[Padded]>,
    done: AtomicUsize,
    /// Helpers registered with the current epoch.
    active: AtomicUsize,
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    sleeping: Vec<AtomicBool>,
    /// Set when the team is dropped: helpers exit.
    stop: AtomicBool,
    /// Tests: milliseconds a helper waits between taking a program and running it.
    #[cfg(test)]
    helper_delay_ms: std::sync::atomic::AtomicU64,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // Nothing panics while holding these locks; recover anyway.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// A team of threads that runs phased programs ([module docs](self)).
pub struct Team {
    shared: Arc<Shared>,
    busy: AtomicBool,
    helpers: Vec<JoinHandle<()>>,
}

impl Drop for Team {
    /// Stops the helpers (waking parked ones) and waits for them to exit.
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        for h in self.helpers.drain(..) {
            h.thread().unpark();
            let _ = h.join();
        }
    }
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Team {{ threads: {} }}", self.threads())
    }
}

/// The team size from `RAYON_NUM_THREADS` (so one setting governs all of vclay's threads) or
/// the available parallelism, capped at [`MAX_TEAM`].
fn team_size() -> usize {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|s| s.parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .min(MAX_TEAM)
}

impl Team {
    /// A team of `threads` (the caller and `threads - 1` helpers; fewer if spawning fails).
    pub fn new(threads: usize) -> Self {
        let want = threads.saturating_sub(1);
        let shared = Arc::new(Shared {
            epoch: AtomicUsize::new(0),
            job: Mutex::new(None),
            claims: (0..MAX_TASKS).map(|_| Padded::default()).collect(),
            done: AtomicUsize::new(0),
            active: AtomicUsize::new(0),
            panic: Mutex::new(None),
            sleeping: (0..want).map(|_| AtomicBool::new(false)).collect(),
            stop: AtomicBool::new(false),
            #[cfg(test)]
            helper_delay_ms: std::sync::atomic::AtomicU64::new(0),
        });
        let mut helpers = Vec::with_capacity(want);
        for i in 0..want {
            let sh = Arc::clone(&shared);
            match std::thread::Builder::new()
                .name(format!("vclay-team-{}", i + 1))
                .spawn(move || helper(&sh, i))
            {
                Ok(h) => helpers.push(h),
                Err(_) => break,
            }
        }
        Self {
            shared,
            busy: AtomicBool::new(false),
            helpers,
        }
    }

    /// The process-wide team, created on first use; `None` when it would have one thread.
    pub fn global() -> Option<&'static Team> {
        static TEAM: OnceLock<Option<Team>> = OnceLock::new();
        TEAM.get_or_init(|| {
            let n = team_size();
            (n > 1).then(|| Team::new(n)).filter(|t| t.threads() > 1)
        })
        .as_ref()
    }

    /// Threads taking part in a program (caller included).
    pub fn threads(&self) -> usize {
        self.helpers.len() + 1
    }

    /// Runs the phased program `counts` / `run` (see the [module docs](self)); returns when
    /// every task has finished. A panic in a task is re-raised here after all tasks finished.
    pub fn run(&self, counts: &[usize], run: &TaskFn<'_>) {
        let total: usize = counts.iter().sum();
        if total > MAX_TASKS
            || self
                .busy
                .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
                .is_err()
        {
            return run_inline(counts, run);
        }
        struct Release<'a>(&'a AtomicBool);
        impl Drop for Release<'_> {
            fn drop(&mut self) {
                self.0.store(false, Ordering::Release);
            }
        }
        let _release = Release(&self.busy);
        let sh = &*self.shared;
        // SAFETY (lifetime erasure): helpers dereference the job only while registered in
        // `active`, and this function waits below until none is registered after closing the
        // epoch, so the borrowed `counts` and `run` outlive every use.
        let job = Job {
            counts: counts as *const [usize],
            run: unsafe { std::mem::transmute::<*const TaskFn<'_>, *const TaskFn<'static>>(run) },
        };
        sh.done.store(0, Ordering::Relaxed);
        *lock(&sh.job) = Some(job);
        let open = sh.epoch.load(Ordering::Relaxed) + 1;
        sh.epoch.store(open, Ordering::SeqCst);
        for (i, h) in self.helpers.iter().enumerate() {
            if sh.sleeping[i].load(Ordering::SeqCst) {
                h.thread().unpark();
            }
        }
        work(sh, open, counts, run, 0, self.threads());
        while sh.done.load(Ordering::Acquire) < total {
            std::hint::spin_loop();
        }
        sh.epoch.store(open + 1, Ordering::SeqCst);
        while sh.active.load(Ordering::SeqCst) > 0 {
            std::hint::spin_loop();
        }
        *lock(&sh.job) = None;
        if let Some(p) = lock(&sh.panic).take() {
            resume_unwind(p);
        }
    }
}

/// Runs a phased program on the [global team](Team::global), or on the calling thread alone
/// when there is none.
pub fn run_phases(counts: &[usize], run: &TaskFn<'_>) {
    match Team::global() {
        Some(t) => t.run(counts, run),
        None => run_inline(counts, run),
    }
}

/// Threads that [`run_phases`] uses (1 without a team).
pub fn team_threads() -> usize {
    Team::global().map_or(1, Team::threads)
}

fn run_inline(counts: &[usize], run: &TaskFn<'_>) {
    for (k, &n) in counts.iter().enumerate() {
        for t in 0..n {
            run(k, t);
        }
    }
}

/// Runs the program's tasks from the thread of rank `rank` (the caller is 0): phase by
/// phase, after the phase's barrier, first the tasks it owns (`task % threads == rank`, so
/// that each thread keeps working on the same part of the data from phase to phase and step
/// to step, in its own cache), then any task still unclaimed (an absent or late owner's).
/// Panics are caught and stored.
///
/// `epoch` is the (odd) epoch of the program, as the thread saw it open: never re-read here.
/// A helper can be delayed between registering and arriving here while the caller runs every
/// task and closes the epoch; re-reading it would then give the closed (even) value, which no
/// claim carries, and the late helper would run the whole program a second time before the
/// caller returns (a race seen once in CI as a test whose tasks ran twice). With the program's
/// own epoch every claim is already taken and the late helper runs nothing.
fn work(
    sh: &Shared,
    epoch: usize,
    counts: &[usize],
    run: &TaskFn<'_>,
    rank: usize,
    threads: usize,
) {
    let mut start = 0;
    for (k, &c) in counts.iter().enumerate() {
        while sh.done.load(Ordering::Acquire) < start {
            std::hint::spin_loop();
        }
        let own = (rank..c).step_by(threads.max(1));
        for t in own.chain(0..c) {
            // Claimed by the first thread to tag it with this epoch.
            let claim = &sh.claims[start + t].0;
            if claim.load(Ordering::Relaxed) == epoch
                || claim.swap(epoch, Ordering::AcqRel) == epoch
            {
                continue;
            }
            if let Err(p) = catch_unwind(AssertUnwindSafe(|| run(k, t))) {
                lock(&sh.panic).get_or_insert(p);
            }
            sh.done.fetch_add(1, Ordering::AcqRel);
        }
        start += c;
    }
}

fn helper(sh: &Shared, idx: usize) {
    let mut seen = 0;
    while let Some(e) = wait_open(sh, idx, seen) {
        seen = e;
        sh.active.fetch_add(1, Ordering::SeqCst);
        if sh.epoch.load(Ordering::SeqCst) == e {
            let job = *lock(&sh.job);
            if let Some(job) = job {
                // SAFETY: registered in `active` while the epoch that posted `job` is open, so
                // the caller is inside `Team::run` and keeps both pointees alive until this
                // helper deregisters below.
                let (counts, run) = unsafe { (&*job.counts, &*job.run) };
                #[cfg(test)]
                std::thread::sleep(Duration::from_millis(
                    sh.helper_delay_ms.load(Ordering::Relaxed),
                ));
                work(sh, e, counts, run, idx + 1, sh.sleeping.len() + 1);
            }
        }
        sh.active.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Waits for an open epoch other than `seen`: spins for [`SPIN`], then parks. `None` when
/// the team is dropped.
fn wait_open(sh: &Shared, idx: usize, seen: usize) -> Option<usize> {
    let ready = |e: usize| !e.is_multiple_of(2) && e != seen;
    let mut since = Instant::now();
    let mut spins = 0u32;
    loop {
        let e = sh.epoch.load(Ordering::Acquire);
        if ready(e) {
            return Some(e);
        }
        if sh.stop.load(Ordering::Acquire) {
            return None;
        }
        spins = spins.wrapping_add(1);
        if spins.is_multiple_of(256) && since.elapsed() > SPIN {
            sh.sleeping[idx].store(true, Ordering::SeqCst);
            if !ready(sh.epoch.load(Ordering::SeqCst)) && !sh.stop.load(Ordering::SeqCst) {
                std::thread::park();
            }
            sh.sleeping[idx].store(false, Ordering::SeqCst);
            since = Instant::now();
        } else {
            std::hint::spin_loop();
        }
    }
}

/// A mutable slice shared by the tasks of a phased program: tasks borrow index ranges for
/// writing ([`SharedSlice::range`]) or the whole slice for reading ([`SharedSlice::read`]).
/// Borrows are checked at run time like a `RefCell`'s, per range: a borrow that overlaps a
/// live conflicting one panics.
pub struct SharedSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    live: Borrows,
    _borrow: PhantomData<&'a mut [T]>,
}

/// Most borrows of one [`SharedSlice`] live at once.
pub const MAX_BORROWS: usize = 32;

/// The live borrows of a [`SharedSlice`] (start, end, writing), behind a spin lock: it is held
/// for a few instructions, and threads meet at it when a phase starts, where a `Mutex` would
/// put one of them to sleep. The lock, the count and the first two borrows share one cache
/// line of their own, so that a claim moves one line between the cores, not three (the count
/// sat after the 32 entries, on another line), and a claim never shares a line with another
/// slice's lock.
#[derive(Default)]
#[repr(C, align(64))]
struct Borrows {
    locked: AtomicBool,
    list: std::cell::UnsafeCell<BorrowList>,
}

#[derive(Default)]
#[repr(C)]
struct BorrowList {
    len: usize,
    items: [(usize, usize, bool); MAX_BORROWS],
}

impl BorrowList {
    fn iter(&self) -> impl Iterator<Item = &(usize, usize, bool)> {
        self.items[..self.len].iter()
    }

    #[track_caller]
    fn push(&mut self, b: (usize, usize, bool)) {
        assert!(
            self.len < MAX_BORROWS,
            "SharedSlice: more than {MAX_BORROWS} live borrows"
        );
        self.items[self.len] = b;
        self.len += 1;
    }

    fn swap_remove(&mut self, i: usize) {
        self.len -= 1;
        self.items[i] = self.items[self.len];
    }
}

impl Borrows {
    fn with<R>(&self, f: impl FnOnce(&mut BorrowList) -> R) -> R {
        // Test, then test-and-set: a waiting thread reads the line (shared) instead of taking
        // it from the holder with every failed exchange.
        while self
            .locked
            .compare_exchange_weak(false, true, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            while self.locked.load(Ordering::Relaxed) {
                std::hint::spin_loop();
            }
        }
        struct Unlock<'a>(&'a AtomicBool);
        impl Drop for Unlock<'_> {
            fn drop(&mut self) {
                self.0.store(false, Ordering::Release);
            }
        }
        let _unlock = Unlock(&self.locked);
        // SAFETY: the lock is held (released by `_unlock`, also when `f` panics), so this is
        // the only reference to the list.
        f(unsafe { &mut *self.list.get() })
    }
}

// SAFETY: the slice is only reached through checked borrows (no two overlapping borrows with
// a writer are live at once), so sharing it between threads is like sharing `&mut [T]` pieces
// (`T: Send`) and `&[T]` (`T: Sync`).
unsafe impl<T: Send + Sync> Sync for SharedSlice<'_, T> {}
unsafe impl<T: Send> Send for SharedSlice<'_, T> {}

impl<T> std::fmt::Debug for SharedSlice<'_, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "SharedSlice {{ len: {} }}", self.len)
    }
}

/// A checked mutable borrow of a range of a [`SharedSlice`].
pub struct RangeMut<'s, 'a, T> {
    owner: &'s SharedSlice<'a, T>,
    range: Range<usize>,
}

/// A checked shared borrow of a whole [`SharedSlice`].
pub struct ReadAll<'s, 'a, T> {
    owner: &'s SharedSlice<'a, T>,
}

impl<T> std::fmt::Debug for RangeMut<'_, '_, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "RangeMut {{ range: {:?} }}", self.range)
    }
}

impl<T> std::fmt::Debug for ReadAll<'_, '_, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ReadAll {{ len: {} }}", self.owner.len)
    }
}

impl<'a, T> SharedSlice<'a, T> {
    /// Shares `s` for the duration of `'a`.
    pub fn new(s: &'a mut [T]) -> Self {
        Self {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            live: Borrows::default(),
            _borrow: PhantomData,
        }
    }

    /// Length of the slice.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the slice is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn claim(&self, r: &Range<usize>, write: bool) {
        self.live.with(|live| {
            let clash = live.iter().any(|&(s, e, w)| {
                (write || w) && s < r.end && r.start < e && !r.is_empty() && s < e
            });
            assert!(
                !clash,
                "SharedSlice: borrow {r:?} ({}) overlaps a live borrow",
                if write { "write" } else { "read" }
            );
            live.push((r.start, r.end, write));
        });
    }

    fn unclaim(&self, r: &Range<usize>, write: bool) {
        self.live.with(|live| {
            let found = live.iter().position(|&b| b == (r.start, r.end, write));
            if let Some(i) = found {
                live.swap_remove(i);
            }
        });
    }

    /// Borrows `range` for writing.
    ///
    /// # Panics
    /// If the range is out of bounds or overlaps a live borrow.
    #[track_caller]
    pub fn range(&self, range: Range<usize>) -> RangeMut<'_, 'a, T> {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "SharedSlice: range {range:?} out of bounds (len {})",
            self.len
        );
        self.claim(&range, true);
        RangeMut { owner: self, range }
    }

    /// Borrows the whole slice for reading.
    ///
    /// # Panics
    /// If a write borrow is live.
    #[track_caller]
    pub fn read(&self) -> ReadAll<'_, 'a, T> {
        self.claim(&(0..self.len), false);
        ReadAll { owner: self }
    }
}

impl<T> Deref for RangeMut<'_, '_, T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        // SAFETY: in bounds (checked in `range`), the pointee outlives `'a`, and no
        // conflicting borrow is live while this one is (checked in `claim`).
        unsafe {
            std::slice::from_raw_parts(self.owner.ptr.add(self.range.start), self.range.len())
        }
    }
}

impl<T> DerefMut for RangeMut<'_, '_, T> {
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as in `deref`; this borrow is the only one overlapping its range.
        unsafe {
            std::slice::from_raw_parts_mut(self.owner.ptr.add(self.range.start), self.range.len())
        }
    }
}

impl<T> Drop for RangeMut<'_, '_, T> {
    fn drop(&mut self) {
        self.owner.unclaim(&self.range, true);
    }
}

impl<T> Deref for ReadAll<'_, '_, T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        // SAFETY: no write borrow is live while this one is (checked in `claim`).
        unsafe { std::slice::from_raw_parts(self.owner.ptr, self.owner.len) }
    }
}

impl<T> Drop for ReadAll<'_, '_, T> {
    fn drop(&mut self) {
        self.owner.unclaim(&(0..self.owner.len), false);
    }
}

/// The borrows of a phased program declared before it runs, so that its tasks reach shared
/// buffers without run-time claims (issue 31; `docs/performance.md` "Level-2 step, session
/// 21").
///
/// A [`SharedSlice`] claim takes the slice's lock, and the threads of a team take it at the
/// same moment when a phase starts, so every claim and release moves a cache line between
/// their cores. A plan states instead, for every slice of the program (numbered `0..slices`),
/// the phases in which its tasks read all of it ([`Plan::read`]) and the range that each task
/// writes ([`Plan::write`]). [`Plan::start`] checks the plan once: in every phase the written
/// ranges are pairwise disjoint, and a slice that is written is not read. A task then gets its
/// declared part ([`PlannedSlice::part`]) or the whole slice ([`PlannedSlice::read`]) through
/// the [`Task`] that the program hands it, with no shared state touched: the checks left are
/// on the task itself (its phase, its program, the slices it has taken).
///
/// Why this is sound: the phases of a program are separated by the team's barriers; a task's
/// borrows cannot outlive the task (they borrow its `&Task`, which lives for one call); a task
/// takes each part once ([`Task`] records it) and cannot be shared with another thread; within
/// a phase the parts of different tasks are disjoint and nobody reads a slice being written
/// (checked by [`Plan::start`]); a [`PlannedSlice`] answers only the tasks of its own program,
/// and a [`Program`] runs once at a time (`run` takes it mutably; its plan stays borrowed
/// mutably while it exists).
///
/// ```
/// use vclay_core::team::Plan;
/// let mut v = vec![0.0; 8];
/// let mut plan = Plan::default();
/// plan.reset(&[2, 1], 1); // two tasks in phase 0, one in phase 1; one slice
/// plan.write(0, 0, 0, 0..4);
/// plan.write(0, 0, 1, 4..8);
/// plan.read(0, 1);
/// let sum = std::sync::Mutex::new(0.0);
/// let mut program = plan.start();
/// let s = program.slice(0, &mut v);
/// program.run(&|task| match task.phase() {
///     0 => s.part(task).1.fill(1.0),
///     _ => *sum.lock().unwrap() = s.read(task).iter().sum(),
/// });
/// assert_eq!(*sum.lock().unwrap(), 8.0);
/// ```
///
/// A part cannot outlive its task (here kept for later):
/// ```compile_fail
/// use vclay_core::team::Plan;
/// let mut v = vec![0.0; 8];
/// let mut plan = Plan::default();
/// plan.reset(&[1], 1);
/// plan.write(0, 0, 0, 0..8);
/// let kept = std::sync::Mutex::new(None);
/// let mut program = plan.start();
/// let s = program.slice(0, &mut v);
/// program.run(&|task| *kept.lock().unwrap() = Some(s.part(task).1));
/// ```
#[derive(Clone, Debug, Default)]
pub struct Plan {
    counts: Vec<usize>,
    /// First task (numbered through the program) of each phase.
    starts: Vec<usize>,
    slices: usize,
    /// `reads[s * phases + k]`: slice `s` is read in phase `k`.
    reads: Vec<bool>,
    /// `writes[s * tasks + starts[k] + t]`: the range that task `t` of phase `k` writes.
    writes: Vec<Range<usize>>,
    /// Per slice, the end of its furthest declared write.
    ends: Vec<usize>,
    /// Scratch of [`Plan::start`].
    sorted: Vec<Range<usize>>,
}

/// Most slices of a planned program (a [`Task`] records the parts it took as bits).
pub const MAX_PLANNED_SLICES: usize = 64;

static PROGRAM_IDS: AtomicUsize = AtomicUsize::new(1);

impl Plan {
    /// Clears the plan for a program of `counts[k]` tasks in phase `k` over `slices` slices
    /// (nothing declared yet); the buffers are kept.
    ///
    /// # Panics
    /// If `slices` exceeds [`MAX_PLANNED_SLICES`].
    #[track_caller]
    pub fn reset(&mut self, counts: &[usize], slices: usize) {
        assert!(
            slices <= MAX_PLANNED_SLICES,
            "Plan: {slices} slices (at most {MAX_PLANNED_SLICES})"
        );
        self.counts.clear();
        self.counts.extend_from_slice(counts);
        self.starts.clear();
        let mut total = 0;
        for &c in counts {
            self.starts.push(total);
            total += c;
        }
        self.slices = slices;
        self.reads.clear();
        self.reads.resize(slices * counts.len(), false);
        self.writes.clear();
        self.writes.resize(slices * total, 0..0);
        self.ends.clear();
        self.ends.resize(slices, 0);
    }

    fn tasks(&self) -> usize {
        self.starts
            .last()
            .map_or(0, |s| s + self.counts[self.counts.len() - 1])
    }

    /// Declares that the tasks of phase `phase` read all of slice `slice`.
    #[track_caller]
    pub fn read(&mut self, slice: usize, phase: usize) {
        assert!(
            slice < self.slices && phase < self.counts.len(),
            "Plan: no such slice or phase"
        );
        self.reads[slice * self.counts.len() + phase] = true;
    }

    /// Declares that task `task` of phase `phase` writes `range` of slice `slice` (an empty
    /// range: nothing).
    #[track_caller]
    pub fn write(&mut self, slice: usize, phase: usize, task: usize, range: Range<usize>) {
        assert!(
            slice < self.slices && phase < self.counts.len() && task < self.counts[phase],
            "Plan: no such slice, phase or task"
        );
        assert!(range.start <= range.end, "Plan: range {range:?} reversed");
        self.ends[slice] = self.ends[slice].max(range.end);
        let i = slice * self.tasks() + self.starts[phase] + task;
        self.writes[i] = range;
    }

    /// Checks the plan and opens it as a program.
    ///
    /// # Panics
    /// If two tasks of a phase write overlapping ranges of a slice, or a slice is written and
    /// read in the same phase.
    #[track_caller]
    pub fn start(&mut self) -> Program<'_> {
        let (phases, tasks) = (self.counts.len(), self.tasks());
        for s in 0..self.slices {
            for k in 0..phases {
                let w = &self.writes[s * tasks + self.starts[k]..][..self.counts[k]];
                self.sorted.clear();
                self.sorted
                    .extend(w.iter().filter(|r| !r.is_empty()).cloned());
                assert!(
                    self.sorted.is_empty() || !self.reads[s * phases + k],
                    "Plan: slice {s} is written and read in phase {k}"
                );
                self.sorted.sort_unstable_by_key(|r| r.start);
                for pair in self.sorted.windows(2) {
                    assert!(
                        pair[0].end <= pair[1].start,
                        "Plan: phase {k} writes overlapping ranges {:?} and {:?} of slice {s}",
                        pair[0],
                        pair[1]
                    );
                }
            }
        }
        Program {
            id: PROGRAM_IDS.fetch_add(1, Ordering::Relaxed),
            plan: self,
        }
    }
}

/// A checked [`Plan`], ready to run ([`Program::run`]); its slices are bound with
/// [`Program::slice`].
#[derive(Debug)]
pub struct Program<'p> {
    id: usize,
    plan: &'p Plan,
}

/// What a task of a [`Program`] is: its phase and index, and the parts it has taken. Handed
/// to the task by [`Program::run`]; it cannot leave the task's thread.
#[derive(Debug)]
pub struct Task {
    program: usize,
    phase: usize,
    index: usize,
    /// Bit `s`: the task has taken its part of slice `s`.
    taken: std::cell::Cell<u64>,
    _not_send: PhantomData<*const ()>,
}

impl Task {
    /// The task's phase.
    pub fn phase(&self) -> usize {
        self.phase
    }

    /// The task's index in its phase.
    pub fn index(&self) -> usize {
        self.index
    }
}

impl<'p> Program<'p> {
    /// Binds `data` as slice `index` of the plan.
    ///
    /// # Panics
    /// If `index` is not a slice of the plan or a declared range ends beyond `data`.
    #[track_caller]
    pub fn slice<'a, T>(&self, index: usize, data: &'a mut [T]) -> PlannedSlice<'p, 'a, T> {
        assert!(index < self.plan.slices, "Plan: no slice {index}");
        assert!(
            self.plan.ends[index] <= data.len(),
            "Plan: slice {index} has {} elements, a declared range ends at {}",
            data.len(),
            self.plan.ends[index]
        );
        PlannedSlice {
            ptr: data.as_mut_ptr(),
            len: data.len(),
            index,
            program: self.id,
            plan: self.plan,
            _borrow: PhantomData,
        }
    }

    /// Runs the program on the [global team](Team::global) (see [`run_phases`]): task `t` of
    /// phase `k` runs as `run(task)`, with `task.phase() == k` and `task.index() == t`.
    pub fn run(&mut self, run: &(dyn Fn(&Task) + Sync)) {
        let program = self.id;
        run_phases(&self.plan.counts, &|phase, index| {
            run(&Task {
                program,
                phase,
                index,
                taken: std::cell::Cell::new(0),
                _not_send: PhantomData,
            });
        });
    }
}

/// A mutable slice bound to a [`Program`]: its tasks reach it as their plan declares, with no
/// run-time claim.
pub struct PlannedSlice<'p, 'a, T> {
    ptr: *mut T,
    len: usize,
    index: usize,
    program: usize,
    plan: &'p Plan,
    _borrow: PhantomData<&'a mut [T]>,
}

// SAFETY: as for `SharedSlice`: the elements are reached only as the checked plan allows
// (disjoint `&mut [T]` parts, `T: Send`, or shared reads, `T: Sync`).
unsafe impl<T: Send + Sync> Sync for PlannedSlice<'_, '_, T> {}
unsafe impl<T: Send> Send for PlannedSlice<'_, '_, T> {}

impl<T> std::fmt::Debug for PlannedSlice<'_, '_, T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "PlannedSlice {{ index: {}, len: {} }}",
            self.index, self.len
        )
    }
}

impl<T> PlannedSlice<'_, '_, T> {
    #[track_caller]
    fn check(&self, task: &Task) {
        assert!(
            task.program == self.program,
            "PlannedSlice: a task of another program"
        );
    }

    /// The range that `task` writes (empty if none).
    #[track_caller]
    pub fn range_of(&self, task: &Task) -> Range<usize> {
        self.check(task);
        let p = self.plan;
        p.writes[self.index * p.tasks() + p.starts[task.phase] + task.index].clone()
    }

    /// The part that `task` declared it writes, with its range (empty if it declared none).
    ///
    /// # Panics
    /// If the task belongs to another program or has taken its part already.
    #[track_caller]
    // The parts that `&self` hands out are disjoint by the checked plan (see the SAFETY note).
    #[allow(clippy::mut_from_ref)]
    pub fn part<'t>(&'t self, task: &'t Task) -> (Range<usize>, &'t mut [T]) {
        let r = self.range_of(task);
        let bit = 1u64 << self.index;
        assert!(
            task.taken.get() & bit == 0,
            "PlannedSlice: part of slice {} taken twice",
            self.index
        );
        task.taken.set(task.taken.get() | bit);
        // SAFETY: `r` is in bounds (its end is at most `ends[index] <= len`, checked in
        // `Program::slice`). Only tasks of this slice's program get here (`check`), and the
        // program runs once at a time (`Program::run` takes it mutably). In this task's phase
        // no other task's declared part overlaps `r` and no task reads the slice (checked in
        // `Plan::start`); this task takes `r` once (`taken`); the borrow lives at most as long
        // as `&'t Task`, i.e. within this task's call, and the phases before and after are
        // separated by the team's barriers. So this is the only live reference to `r`.
        let part = unsafe { std::slice::from_raw_parts_mut(self.ptr.add(r.start), r.len()) };
        (r, part)
    }

    /// The whole slice, for a task of a phase that declared it reads it.
    ///
    /// # Panics
    /// If the task belongs to another program or its phase does not read the slice.
    #[track_caller]
    pub fn read<'t>(&'t self, task: &'t Task) -> &'t [T] {
        self.check(task);
        let p = self.plan;
        assert!(
            p.reads[self.index * p.counts.len() + task.phase],
            "PlannedSlice: phase {} does not read slice {}",
            task.phase,
            self.index
        );
        // SAFETY: no task writes this slice in a phase that reads it (checked in
        // `Plan::start`), the other phases are separated by the team's barriers and borrows
        // end with their task's call (`'t`), so no `&mut` to any element is live meanwhile.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A three-phase program whose later phases read what earlier ones wrote.
    fn program(team: Option<&Team>, n: usize) -> Vec<f64> {
        let mut a = vec![0.0; n];
        let mut b = vec![0.0; n];
        let sa = SharedSlice::new(&mut a);
        let sb = SharedSlice::new(&mut b);
        let tasks = 7;
        let chunk = |t: usize| n * t / tasks..n * (t + 1) / tasks;
        let run = |k: usize, t: usize| match k {
            0 => {
                let r = chunk(t);
                let mut w = sa.range(r.clone());
                for (i, x) in r.zip(w.iter_mut()) {
                    *x = (i as f64).sin();
                }
            }
            1 => {
                // Reads all of `a` (written by every task of phase 0).
                let a = sa.read();
                let r = chunk(t);
                let mut w = sb.range(r.clone());
                for (i, x) in r.zip(w.iter_mut()) {
                    *x = a[i] + a[(i * 7 + 3) % n];
                }
            }
            _ => {
                let b = sb.read();
                let mut w = sa.range(0..n);
                for (x, y) in w.iter_mut().zip(b.iter()) {
                    *x = 2.0 * y;
                }
            }
        };
        match team {
            Some(team) => team.run(&[tasks, tasks, 1], &run),
            None => run_inline(&[tasks, tasks, 1], &run),
        }
        sa.read().to_vec()
    }

    /// The three-phase program of [`program`] with declared borrows.
    fn planned_program(plan: &mut Plan, n: usize) -> Vec<f64> {
        let mut a = vec![0.0; n];
        let mut b = vec![0.0; n];
        let tasks = 7;
        let chunk = |t: usize| n * t / tasks..n * (t + 1) / tasks;
        plan.reset(&[tasks, tasks, 1], 2);
        for t in 0..tasks {
            plan.write(0, 0, t, chunk(t));
            plan.write(1, 1, t, chunk(t));
        }
        plan.read(0, 1);
        plan.read(1, 2);
        plan.write(0, 2, 0, 0..n);
        let mut prog = plan.start();
        let (sa, sb) = (prog.slice(0, &mut a), prog.slice(1, &mut b));
        prog.run(&|task| match task.phase() {
            0 => {
                let (r, w) = sa.part(task);
                for (i, x) in r.zip(w.iter_mut()) {
                    *x = (i as f64).sin();
                }
            }
            1 => {
                let a = sa.read(task);
                let (r, w) = sb.part(task);
                for (i, x) in r.zip(w.iter_mut()) {
                    *x = a[i] + a[(i * 7 + 3) % n];
                }
            }
            _ => {
                let b = sb.read(task);
                let (_, w) = sa.part(task);
                for (x, y) in w.iter_mut().zip(b) {
                    *x = 2.0 * y;
                }
            }
        });
        a
    }

    /// Issue 31 (session h56): a program whose borrows are declared in a plan computes what
    /// the same program with run-time claims computes, on the team and on one thread, and a
    /// plan is reused from run to run.
    #[test]
    fn a_planned_program_computes_what_the_claimed_program_computes() {
        let want = program(None, 1000);
        let mut plan = Plan::default();
        for _ in 0..200 {
            assert_eq!(planned_program(&mut plan, 1000), want);
        }
        assert_eq!(planned_program(&mut plan, 333), program(None, 333));
    }

    #[test]
    #[should_panic(expected = "writes overlapping ranges")]
    fn a_plan_with_overlapping_writes_panics_when_started() {
        let mut plan = Plan::default();
        plan.reset(&[1, 2], 1);
        plan.write(0, 1, 0, 0..6);
        plan.write(0, 1, 1, 5..10);
        plan.start();
    }

    #[test]
    #[should_panic(expected = "written and read in phase 0")]
    fn a_plan_that_reads_a_slice_it_writes_in_the_same_phase_panics_when_started() {
        let mut plan = Plan::default();
        plan.reset(&[2], 1);
        plan.write(0, 0, 1, 0..3);
        plan.read(0, 0);
        plan.start();
    }

    #[test]
    #[should_panic(expected = "declared range ends at 12")]
    fn a_slice_shorter_than_its_plan_panics_when_bound() {
        let mut plan = Plan::default();
        plan.reset(&[2], 1);
        plan.write(0, 0, 1, 6..12);
        let prog = plan.start();
        let mut v = vec![0; 10];
        prog.slice(0, &mut v);
    }

    /// Runs `task` as the only task of a one-slice program (slice 0: 10 elements, the task
    /// writes 0..5 and nothing is read); returns the panic message, if any.
    fn misuse(task: impl Fn(&PlannedSlice<'_, '_, i32>, &Task) + Sync) -> Option<String> {
        let mut plan = Plan::default();
        plan.reset(&[1], 1);
        plan.write(0, 0, 0, 0..5);
        let mut prog = plan.start();
        let mut v = vec![0; 10];
        let s = prog.slice(0, &mut v);
        let r = catch_unwind(AssertUnwindSafe(|| prog.run(&|t| task(&s, t))));
        r.err().map(|p| {
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        })
    }

    #[test]
    fn a_planned_slice_refuses_every_undeclared_borrow() {
        // The declared part, once: fine.
        assert_eq!(
            misuse(|s, t| {
                s.part(t).1[4] = 1;
            }),
            None
        );
        // Twice in one task: two `&mut` to one range.
        let twice = misuse(|s, t| {
            let (_, a) = s.part(t);
            let (_, b) = s.part(t);
            a[0] = 1;
            b[0] = 2;
        });
        assert!(twice.unwrap().contains("taken twice"));
        // A read in a phase that writes the slice.
        let read = misuse(|s, t| {
            s.read(t);
        });
        assert!(read.unwrap().contains("does not read slice 0"));
        // A task of another program (here one nested inside the task).
        let other = misuse(|s, _| {
            let mut plan = Plan::default();
            plan.reset(&[1], 1);
            plan.write(0, 0, 0, 0..1);
            plan.start().run(&|inner| {
                s.part(inner);
            });
        });
        assert!(other.unwrap().contains("another program"));
    }

    #[test]
    fn a_team_computes_what_one_thread_computes() {
        let team = Team::new(3);
        let want = program(None, 1000);
        for _ in 0..200 {
            assert_eq!(program(Some(&team), 1000), want);
        }
        // Sleeping helpers are woken.
        std::thread::sleep(SPIN * 3);
        assert_eq!(program(Some(&team), 1000), want);
    }

    #[test]
    fn dropping_a_team_ends_its_helpers() {
        let team = Team::new(3);
        let ran = AtomicUsize::new(0);
        team.run(&[6], &|_, _| {
            ran.fetch_add(1, Ordering::Relaxed);
        });
        // One helper parked, one spinning: both must exit (the drop joins them).
        std::thread::sleep(SPIN * 3);
        drop(team);
        assert_eq!(ran.load(Ordering::Relaxed), 6);
    }

    #[test]
    fn a_program_started_from_a_task_runs_inline() {
        let team = Team::new(2);
        let hits = AtomicUsize::new(0);
        team.run(&[2], &|_, _| {
            team.run(&[3], &|_, _| {
                hits.fetch_add(1, Ordering::Relaxed);
            });
        });
        assert_eq!(hits.load(Ordering::Relaxed), 6);
    }

    #[test]
    fn a_helper_that_arrives_after_the_program_finished_runs_nothing() {
        // The helper takes the program, then is delayed past its end: the caller runs every
        // task, closes the epoch and waits for the helper, which must not run the tasks again
        // (it did when it read the closed epoch instead of its program's).
        let team = Team::new(2);
        team.shared.helper_delay_ms.store(60, Ordering::Relaxed);
        for _ in 0..3 {
            let ran = AtomicUsize::new(0);
            team.run(&[3, 2], &|_, _| {
                std::thread::sleep(Duration::from_millis(3));
                ran.fetch_add(1, Ordering::Relaxed);
            });
            assert_eq!(ran.load(Ordering::Relaxed), 5);
        }
    }

    #[test]
    fn a_panicking_task_is_reraised_after_the_program() {
        let team = Team::new(2);
        let ran = AtomicUsize::new(0);
        let r = catch_unwind(AssertUnwindSafe(|| {
            team.run(&[4, 4], &|k, t| {
                ran.fetch_add(1, Ordering::Relaxed);
                assert!(!(k == 0 && t == 2), "task failed");
            })
        }));
        assert!(r.is_err());
        assert_eq!(ran.load(Ordering::Relaxed), 8);
        // The team is usable afterwards.
        let again = AtomicUsize::new(0);
        team.run(&[5], &|_, _| {
            again.fetch_add(1, Ordering::Relaxed);
        });
        assert_eq!(again.load(Ordering::Relaxed), 5);
    }

    /// Issue 31 (session h54): the borrow list's spin lock waits by reading the flag before it
    /// tries to take it (test, then test-and-set). Threads that claim and release disjoint
    /// ranges of one slice all the time must never see a clash, and the list must end empty.
    #[test]
    fn concurrent_claims_of_disjoint_ranges_never_clash_and_leave_no_borrow() {
        let mut v = vec![0usize; 40];
        let s = SharedSlice::new(&mut v);
        std::thread::scope(|scope| {
            for t in 0..4 {
                let s = &s;
                scope.spawn(move || {
                    for i in 0..20_000 {
                        let mut w = s.range(10 * t..10 * t + 10);
                        w[i % 10] += 1;
                    }
                });
            }
        });
        // Every borrow was released: the whole slice can be borrowed for writing.
        let all = s.range(0..40);
        assert_eq!(all.iter().sum::<usize>(), 80_000);
    }

    #[test]
    #[should_panic(expected = "overlaps a live borrow")]
    fn overlapping_write_borrows_panic() {
        let mut v = vec![0; 10];
        let s = SharedSlice::new(&mut v);
        let _a = s.range(0..6);
        let _b = s.range(5..10);
    }

    #[test]
    fn disjoint_borrows_and_reads_after_release_work() {
        let mut v = vec![0; 10];
        let s = SharedSlice::new(&mut v);
        {
            let mut a = s.range(0..5);
            let mut b = s.range(5..10);
            a[0] = 1;
            b[4] = 2;
        }
        let r = s.read();
        let r2 = s.read();
        assert_eq!(r[0] + r2[9], 3);
    }
}

//! The memory budget (`--mem`) and every share of it. Each share below
//! has a name, the reason for its size, and this one place where it is
//! computed; the shares that are alive at the same time sum to at most the
//! budget ([`Budget::phases`], checked by the tests for every budget and
//! thread count). The default budget of every command is
//! [`default_mem_bytes`].
//!
//! Phases of one run follow each other, so each phase may use the whole
//! budget: the discretize stage (mapped faces, or the sorted dereference),
//! the reconstruct stage (sub-slabs in flight), and `mint check`'s passes.

/// The default heap budget of every command: a quarter of the machine's
/// memory (`MemTotal` of /proc/meminfo), or 2 GiB where that is unknown.
pub fn default_mem_bytes() -> u64 {
    let total = || -> Option<u64> {
        let s = std::fs::read_to_string("/proc/meminfo").ok()?;
        let kb: u64 = s.lines().find(|l| l.starts_with("MemTotal:"))?.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb * 1024)
    };
    total().map_or(2 << 30, |r| r / 4)
}

/// Help text of every command's `--mem`, with the default stated here.
pub const MEM_HELP: &str = "Heap budget, e.g. 512M or 2G: it decides slab thickness and when to spill to disk, never the input's size [default: a quarter of RAM]";

const MIB: u64 = 1 << 20;

/// A heap budget, handed out in named shares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// What was asked (`--mem`).
    requested: u64,
    threads: u64,
}

impl Budget {
    /// Heap kept aside in every engine task for the reader's channels, its
    /// chunk buffers (64K triangles each, a few per thread) and the shard
    /// writers' buffers.
    pub const RESERVE: u64 = 48 * MIB;
    /// The smallest budget an engine task runs in: the reserve and 16 MiB of
    /// work. A smaller `--mem` is raised to it.
    pub const MIN: u64 = Self::RESERVE + 16 * MIB;
    /// `mint check`'s floor and ceiling. Past about 512 MiB more memory
    /// only slows the check (first-touch faults on the buckets, vertex
    /// blocks too large for the caches; 100M faces: 9.7 s at 256M and
    /// 512M, 13 s at 1G, 14.5 s at 5.9G); spilled buckets come back from
    /// the page cache anyway.
    pub const CHECK_MIN: u64 = 16 * MIB;
    pub const CHECK_MAX: u64 = 512 * MIB;
    /// Least bytes of `check`'s face buckets, whatever the vertices take.
    pub const CHECK_MIN_BUCKETS: u64 = 8 * MIB;

    /// `requested` bytes shared by `threads` workers (at least one).
    pub fn new(requested: u64, threads: usize) -> Budget {
        Budget { requested, threads: threads.max(1) as u64 }
    }

    /// What was asked.
    pub fn requested(&self) -> u64 {
        self.requested
    }

    /// The budget an engine task works in: the request, at least [`Self::MIN`].
    pub fn total(&self) -> u64 {
        self.requested.max(Self::MIN)
    }

    /// What is left after the reserve.
    fn working(&self) -> u64 {
        self.total() - Self::RESERVE
    }

    /// The sorted dereference's whole share (its buckets and their spill
    /// buffers): everything but the reserve.
    pub fn sort(&self) -> u64 {
        self.working()
    }

    /// A volume's discretize task (mint-pipeline's `discretize_planes`): its
    /// slices, two node planes and a group of bands' crossings. Nothing
    /// else of the task is alive then: everything but the reserve.
    pub fn volume(&self) -> u64 {
        self.working()
    }

    /// One worker's corner buckets in the sort's scatter pass, and again
    /// one worker's position buckets in its gather pass: 45% of the sort's
    /// share over the workers for each, so that both sets (alive together
    /// while the gather reads the scatter's) and the allocator's slack fit.
    pub fn sort_buckets_per_thread(&self) -> u64 {
        self.sort() * 45 / 100 / self.threads
    }

    /// One sub-slab in flight during reconstruction. Each worker holds one
    /// slab being built, and the ordered writer up to two finished ones
    /// waiting for their turn: `threads + 2` in all.
    /// The engine's tables with one entry per slab-axis layer (records per
    /// plane in every discretize result, their sum): half the working
    /// memory. A grid with more layers than fit is refused.
    pub fn layer_tables(&self) -> u64 {
        self.working() / 2
    }

    pub fn slab_in_flight(&self) -> u64 {
        self.working() / (self.threads + 2)
    }

    /// `mint check`'s budget: the request within [`Self::CHECK_MIN`] and
    /// [`Self::CHECK_MAX`].
    pub fn check(&self) -> u64 {
        self.requested.clamp(Self::CHECK_MIN, Self::CHECK_MAX)
    }

    /// One worker's buckets of hashed positions in `check`'s weld: 5/8 of
    /// the check's budget over the workers (the rest: each bucket's table
    /// while it is judged, a sixteenth, and slack).
    pub fn check_weld_per_thread(&self) -> u64 {
        self.check() / 8 * 5 / self.threads
    }

    /// The size of one bucket of `check`'s weld: a sixteenth of its budget.
    pub fn check_weld_bucket(&self) -> u64 {
        (self.check() / 16).max(1)
    }

    /// `check`'s face buckets (all workers together) once `per_vertex`
    /// bytes are kept for the vertices (union-find, bit sets, the weld's
    /// map): half of the rest, since judging a block and the allocator need
    /// room too; never below [`Self::CHECK_MIN_BUCKETS`].
    pub fn check_face_buckets(&self, per_vertex: u64) -> u64 {
        (self.check().saturating_sub(per_vertex) / 2).max(Self::CHECK_MIN_BUCKETS)
    }

    /// Of the face buckets, the collapsed faces' share: an eighth more.
    pub fn check_collapsed_buckets(&self, per_vertex: u64) -> u64 {
        self.check_face_buckets(per_vertex) / 8
    }

    /// Every phase's shares that are alive together, by name, with the
    /// budget they must fit: for the tests, and for anyone who wants to see
    /// where the memory goes. `vertex_bytes` is what `check` keeps per
    /// vertex for a mesh (see [`Self::check_face_buckets`]).
    pub fn phases(&self, vertex_bytes: u64) -> Vec<(&'static str, u64, Vec<(&'static str, u64)>)> {
        let t = self.threads;
        vec![
            ("discretize, sorted dereference", self.total(), vec![("reserve", Self::RESERVE), ("scatter buckets", t * self.sort_buckets_per_thread()), ("gather buckets", t * self.sort_buckets_per_thread())]),
            ("discretize, volume", self.total(), vec![("reserve", Self::RESERVE), ("slices, planes and bands", self.volume())]),
            ("reconstruct", self.total(), vec![("reserve", Self::RESERVE), ("sub-slabs in flight", (t + 2) * self.slab_in_flight())]),
            ("check: weld", self.check(), vec![("weld buckets", t * self.check_weld_per_thread()), ("bucket table", self.check_weld_bucket())]),
            (
                "check: faces",
                self.check().max(vertex_bytes + 2 * Self::CHECK_MIN_BUCKETS),
                vec![("vertices", vertex_bytes), ("face buckets", self.check_face_buckets(vertex_bytes)), ("collapsed buckets", self.check_collapsed_buckets(vertex_bytes))],
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_to_at_most_the_budget() {
        let mems = [0, 1, 16 * MIB, 48 * MIB, 63 * MIB, 64 * MIB, 100 * MIB, 256 * MIB, 513 * MIB, 2 << 30, 6 << 30, 1 << 40];
        for mem in mems {
            for threads in [0, 1, 2, 3, 8, 64, 256] {
                let b = Budget::new(mem, threads);
                assert!(b.total() >= mem.min(Budget::MIN) && b.total() >= Budget::MIN);
                for vertex_bytes in [0, MIB, b.check() / 3, 10 << 30] {
                    for (phase, limit, shares) in b.phases(vertex_bytes) {
                        let sum: u64 = shares.iter().map(|s| s.1).sum();
                        assert!(sum <= limit, "--mem {mem}, {threads} threads, {vertex_bytes} vertex bytes: {phase} shares {shares:?} sum {sum} > {limit}");
                        assert!(shares.iter().all(|s| s.1 > 0 || s.0 == "vertices"), "{phase}: an empty share {shares:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_budget_at_the_floor_keeps_sixteen_mib_of_work() {
        assert_eq!(Budget::new(1, 1).sort(), 16 * MIB);
        assert_eq!(Budget::new(1 << 30, 2).slab_in_flight(), ((1 << 30) - Budget::RESERVE) / 4);
        assert_eq!(Budget::new(1, 4).check(), Budget::CHECK_MIN);
        assert_eq!(Budget::new(1 << 40, 4).check(), Budget::CHECK_MAX);
    }
}

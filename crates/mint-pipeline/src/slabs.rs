//! Slabs in memory: [`plan_slabs`] cuts a layer range into sub-slabs that
//! fit the budget, and [`reconstruct_ordered`] reconstructs them on every
//! thread, handing results on strictly in order with at most `threads + 1`
//! of them in memory.

use crate::error::PipelineError;
use crate::progress::{check_cancel, Progress};
use mint_core::cells::SlabResult;
use mint_core::colour::Rgba;
use mint_core::signs::RepairStats;
use mint_core::FilterStats;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};

/// Estimated heap bytes per stored record while its slab is reconstructed:
/// the record, its vertex, about two faces, active-cell ids, and slack.
pub const BYTES_PER_RECORD_IN_SLAB: u64 = 128;
/// What a record costs on top of [`BYTES_PER_RECORD_IN_SLAB`] in a coloured
/// run: its coloured copy (24 bytes) and its vertex's colour.
pub const COLOUR_BYTES_PER_RECORD_IN_SLAB: u64 = 32;

/// Estimated heap bytes per plane of a slab being reconstructed, whatever
/// its records: each plane holds a few vectors (records, edge vertices, S
/// records; about 64 bytes each with the allocator's header) and about four
/// copies of its node states (one bit per node of the cross-section).
/// Without this a grid of many nearly empty layers (a needle 10⁷ cells long)
/// planned sub-slabs of millions of planes and overran the budget 2-3×.
pub fn bytes_per_plane(na: u32, nb: u32) -> u64 {
    let nodes = (na as u64 + 1) * (nb as u64 + 1);
    512 + 4 * nodes.div_ceil(64) * 8
}

/// Splits layers `first .. ns` into slabs `(k0, k1)`: layers `k0 .. k1`,
/// reading planes `k0 ..= k1`. With `fixed`, every slab has that many
/// layers; otherwise slabs grow while their planes (`plane_bytes` each) and
/// records fit `budget` bytes (never below one layer).
pub fn plan_slabs(counts: &[u64], first: u32, ns: u32, fixed: Option<u32>, budget: u64, plane_bytes: u64) -> Vec<(u32, u32)> {
    let mut slabs = Vec::new();
    let mut k0 = first;
    while k0 < ns {
        let mut k1 = k0 + 1;
        match fixed {
            Some(n) => k1 = (k0 + n.max(1)).min(ns),
            None => {
                let bytes = |k: u32| counts.get(k as usize).copied().unwrap_or(0) * BYTES_PER_RECORD_IN_SLAB + plane_bytes;
                let mut used = bytes(k0) + bytes(k1);
                while k1 < ns && used + bytes(k1 + 1) <= budget {
                    k1 += 1;
                    used += bytes(k1);
                }
            }
        }
        slabs.push((k0, k1));
        k0 = k1;
    }
    slabs
}

/// What one slab's reconstruction returns.
/// A slab's result, its vertices' colours (empty when the run carries
/// none), and its counters.
pub(crate) type Done = (SlabResult, Vec<Rgba>, FilterStats, RepairStats);

/// Reconstructs `slabs` on `threads` workers and hands results to `emit`
/// strictly in slab order. At most `threads + 1` slabs are held at once.
pub(crate) fn reconstruct_ordered(
    slabs: &[(u32, u32)],
    threads: usize,
    compute: &(dyn Fn(u32, u32) -> Result<Done, PipelineError> + Sync),
    progress: &dyn Progress,
    emit: &mut dyn FnMut(SlabResult, Vec<Rgba>, FilterStats, RepairStats, u64) -> Result<(), PipelineError>,
) -> Result<(), PipelineError> {
    let window = threads as u64 + 1;
    let next = AtomicU64::new(0);
    let written = (Mutex::new(0u64), Condvar::new());
    let stop = std::sync::atomic::AtomicBool::new(false);
    let (tx, rx) = crossbeam_channel::unbounded::<(u64, Result<Done, PipelineError>)>();
    std::thread::scope(|s| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, written, stop) = (&next, &written, &stop);
            s.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= slabs.len() as u64 || stop.load(Ordering::SeqCst) {
                    return;
                }
                {
                    let (lock, cv) = written;
                    let mut w = lock.lock().unwrap();
                    while i >= *w + window && !stop.load(Ordering::SeqCst) {
                        w = cv.wait(w).unwrap();
                    }
                }
                let (k0, k1) = slabs[i as usize];
                let r = compute(k0, k1);
                if tx.send((i, r)).is_err() {
                    return;
                }
            });
        }
        drop(tx);
        let mut pending = std::collections::BTreeMap::new();
        let mut want = 0u64;
        let mut outcome = Ok(());
        for (i, r) in rx.iter() {
            pending.insert(i, r);
            while let Some(r) = pending.remove(&want) {
                let step = r.and_then(|(res, colours, f, rep)| {
                    let (k0, k1) = slabs[want as usize];
                    emit(res, colours, f, rep, (k1 - k0) as u64)
                });
                let step = step.and_then(|_| check_cancel(progress));
                if let Err(e) = step {
                    outcome = Err(e);
                    stop.store(true, Ordering::SeqCst);
                }
                want += 1;
                let (lock, cv) = &written;
                *lock.lock().unwrap() = want;
                cv.notify_all();
                if outcome.is_err() {
                    break;
                }
            }
            if outcome.is_err() {
                break;
            }
        }
        if outcome.is_err() {
            stop.store(true, Ordering::SeqCst);
            let (lock, cv) = &written;
            *lock.lock().unwrap() = u64::MAX / 2;
            cv.notify_all();
        }
        outcome
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_slabs_cover_every_layer_once() {
        let counts = vec![5u64; 11];
        assert_eq!(plan_slabs(&counts, 0, 10, Some(3), 0, 0), vec![(0, 3), (3, 6), (6, 9), (9, 10)]);
        assert_eq!(plan_slabs(&counts, 0, 10, Some(1), 0, 0).len(), 10);
    }

    #[test]
    fn budget_slabs_grow_until_full_but_never_below_one_layer() {
        let counts = vec![10u64; 11];
        let per = 10 * BYTES_PER_RECORD_IN_SLAB;
        assert_eq!(plan_slabs(&counts, 0, 10, None, 0, 0).len(), 10);
        // Room for 4 planes = 3 layers.
        let s = plan_slabs(&counts, 0, 10, None, 4 * per, 0);
        assert_eq!(s[0], (0, 3));
        assert_eq!(s.last().unwrap().1, 10);
        assert_eq!(plan_slabs(&counts, 0, 10, None, u64::MAX, 0), vec![(0, 10)]);
    }
}

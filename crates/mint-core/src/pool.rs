//! The one worker pool of mint's parallel passes (the engine's, `check`'s): `threads` scoped workers take numbered
//! items (chunks of faces, vertex blocks, buckets) from a shared counter,
//! in order, until the items run out or one fails; the first error wins
//! and stops the others before their next item. The calling thread may run
//! something beside them, typically the writer that drains what they send,
//! and can stop them too (through the flag it is handed).
//!
//! Which worker takes which item varies from run to run; every caller puts
//! results back in item order, so outputs do not depend on it.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

/// Runs `work(&mut state, item)` for every item in `0..items` on `threads`
/// workers, each with its own `state`, made by `make(worker)` on the
/// calling thread before they start (`make` is dropped before `beside`
/// runs) and handed to `finish` when the worker ends (so that a channel
/// sender in it closes), while the calling thread runs `beside(stop)`.
/// Returns the first error of a worker (`None`: every item ran), what each
/// worker's `finish` returned (in worker order), and what `beside`
/// returned. Setting `stop` makes the workers end before their next item.
pub fn run<W, T, E, R>(
    threads: usize,
    items: u64,
    make: impl FnMut(usize) -> W,
    work: impl Fn(&mut W, u64) -> Result<(), E> + Sync,
    finish: impl Fn(W) -> T + Sync,
    beside: impl FnOnce(&AtomicBool) -> R,
) -> (Option<E>, Vec<T>, R)
where
    W: Send,
    T: Send,
    E: Send,
{
    let states: Vec<W> = (0..threads.max(1)).map(make).collect();
    let next = AtomicU64::new(0);
    let stop = AtomicBool::new(false);
    let failed: Mutex<Option<E>> = Mutex::new(None);
    let (finished, r) = std::thread::scope(|s| {
        let workers: Vec<_> = states
            .into_iter()
            .map(|mut state| {
                let (next, stop, failed, work, finish) = (&next, &stop, &failed, &work, &finish);
                s.spawn(move || {
                    loop {
                        if stop.load(Ordering::Relaxed) {
                            break;
                        }
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if i >= items {
                            break;
                        }
                        if let Err(e) = work(&mut state, i) {
                            failed.lock().unwrap().get_or_insert(e);
                            stop.store(true, Ordering::Relaxed);
                            break;
                        }
                    }
                    finish(state)
                })
            })
            .collect();
        let r = beside(&stop);
        (workers.into_iter().map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p))).collect(), r)
    });
    (failed.into_inner().unwrap(), finished, r)
}

/// [`run`] with nothing beside the workers: `Err` on the first failure,
/// else what each worker's `finish` returned, in worker order.
pub fn collect<W: Send, T: Send, E: Send>(threads: usize, items: u64, make: impl FnMut(usize) -> W, work: impl Fn(&mut W, u64) -> Result<(), E> + Sync, finish: impl Fn(W) -> T + Sync) -> Result<Vec<T>, E> {
    match run(threads, items, make, work, finish, |_| ()) {
        (Some(e), _, ()) => Err(e),
        (None, v, ()) => Ok(v),
    }
}

/// [`collect`] of nothing: `Err` on the first failure.
pub fn for_each<W: Send, E: Send>(threads: usize, items: u64, make: impl FnMut(usize) -> W, work: impl Fn(&mut W, u64) -> Result<(), E> + Sync) -> Result<(), E> {
    collect(threads, items, make, work, drop).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    #[test]
    fn every_item_runs_once_and_the_first_error_stops_the_rest() {
        for threads in [1, 2, 5] {
            let seen: Vec<AtomicUsize> = (0..1000).map(|_| AtomicUsize::new(0)).collect();
            for_each(threads, 1000, |_| (), |_, i| -> Result<(), ()> {
                seen[i as usize].fetch_add(1, Ordering::Relaxed);
                Ok(())
            })
            .unwrap();
            assert!(seen.iter().all(|s| s.load(Ordering::Relaxed) == 1));
            let ran = AtomicUsize::new(0);
            let e = for_each(threads, 1_000_000, |_| (), |_, i| {
                ran.fetch_add(1, Ordering::Relaxed);
                if i == 10 {
                    Err(i)
                } else {
                    Ok(())
                }
            });
            assert_eq!(e, Err(10));
            assert!(ran.load(Ordering::Relaxed) < 1000, "the error did not stop the workers");
        }
    }

    #[test]
    fn states_are_dropped_when_workers_end_and_beside_can_stop_them() {
        let (tx, rx) = crossbeam_channel::bounded::<u64>(4);
        let (e, _, sum) = run(3, 100, move |_| tx.clone(), |tx, i| tx.send(i).map_err(|_| "closed"), drop, |_| rx.iter().sum::<u64>());
        assert_eq!((e, sum), (None, 4950));
        let (e, _, ()) = run(2, u64::MAX, |_| (), |_, _| -> Result<(), ()> { Ok(()) }, drop, |stop| stop.store(true, Ordering::Relaxed));
        assert_eq!(e, None);
        // Each worker's state comes back, in worker order.
        let counts = collect(3, 300, |w| (w, 0u64), |(_, n), _| -> Result<(), ()> {
            *n += 1;
            Ok(())
        }, |s| s)
        .unwrap();
        assert_eq!(counts.iter().map(|c| c.0).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(counts.iter().map(|c| c.1).sum::<u64>(), 300);
    }
}

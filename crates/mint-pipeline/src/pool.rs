//! The engine's one worker pool: `threads` scoped workers take numbered
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
/// calling thread before they start and dropped when the worker ends (so
/// that a channel sender in it closes; `make` itself is dropped before
/// `beside` runs), while the calling thread runs `beside(stop)`. Returns
/// the first error of a worker (`None`: every item ran) and what `beside`
/// returned. Setting `stop` makes the workers end before their next item.
pub fn run<W, E, R>(threads: usize, items: u64, make: impl FnMut(usize) -> W, work: impl Fn(&mut W, u64) -> Result<(), E> + Sync, beside: impl FnOnce(&AtomicBool) -> R) -> (Option<E>, R)
where
    W: Send,
    E: Send,
{
    let states: Vec<W> = (0..threads.max(1)).map(make).collect();
    let next = AtomicU64::new(0);
    let stop = AtomicBool::new(false);
    let failed: Mutex<Option<E>> = Mutex::new(None);
    let r = std::thread::scope(|s| {
        for mut state in states {
            let (next, stop, failed, work) = (&next, &stop, &failed, &work);
            s.spawn(move || loop {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= items {
                    return;
                }
                if let Err(e) = work(&mut state, i) {
                    failed.lock().unwrap().get_or_insert(e);
                    stop.store(true, Ordering::Relaxed);
                    return;
                }
            });
        }
        beside(&stop)
    });
    (failed.into_inner().unwrap(), r)
}

/// [`run`] with nothing beside the workers: `Err` on the first failure.
pub fn for_each<W: Send, E: Send>(threads: usize, items: u64, make: impl FnMut(usize) -> W, work: impl Fn(&mut W, u64) -> Result<(), E> + Sync) -> Result<(), E> {
    match run(threads, items, make, work, |_| ()) {
        (Some(e), ()) => Err(e),
        (None, ()) => Ok(()),
    }
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
        let (e, sum) = run(3, 100, move |_| tx.clone(), |tx, i| tx.send(i).map_err(|_| "closed"), |_| rx.iter().sum::<u64>());
        assert_eq!((e, sum), (None, 4950));
        let (e, ()) = run(2, u64::MAX, |_| (), |_, _| -> Result<(), ()> { Ok(()) }, |stop| stop.store(true, Ordering::Relaxed));
        assert_eq!(e, None);
    }
}

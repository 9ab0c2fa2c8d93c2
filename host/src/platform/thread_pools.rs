//! Worker threads. Pools, one per thread count, started once and kept for the process:
//! a caller tracing batch after batch (`trace --runs`, an animation's frames, a sweep of
//! renders) does not start threads for every batch, and its workers keep their caches
//! warm.
//! (On Sponza's 8×8 packets, two threads, 20 runs per call: a median of 35.6 against
//! 33.6 Mrays/s with a fresh pool per batch, within this machine's spread.)

use std::sync::{Arc, Mutex};

use anyhow::{anyhow, Result};

/// The pools started so far, by requested thread count (`None`: all cores).
static POOLS: Mutex<Vec<(Option<usize>, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());

/// The pool of `threads` workers (all cores when `None`), started on first use.
pub fn thread_pool(threads: Option<usize>) -> Result<Arc<rayon::ThreadPool>> {
    let threads = threads.map(|n| n.max(1));
    // A poisoned lock only means another thread panicked while holding it; the list of
    // pools is still whole (a push either happened or not).
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, pool)) = pools.iter().find(|(n, _)| *n == threads) {
        return Ok(pool.clone());
    }
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        b = b.num_threads(n);
    }
    let pool = Arc::new(b.build().map_err(|e| anyhow!("cannot start worker threads: {e}"))?);
    pools.push((threads, pool.clone()));
    Ok(pool)
}

/// Runs `work` on every item of `items` on `threads` threads (all cores when `None`),
/// each taking the next item as it finishes the last (self-scheduling from a shared
/// iterator); one thread runs on the caller's. Rayon's `par_iter` splits the items
/// into halves per worker first and steals later: on 256 chunks of one image, whose
/// cost varies a hundredfold between sky and geometry, Sponza's 8×8 packets ran on two
/// threads at 26 Mrays/s against 20 on one; taking chunk by chunk, 40 (2.0×). The helpers
/// are a kept pool's `threads − 1` workers, in a scope on the caller's thread, not
/// threads started per call: a batch of 78 thousand shadow rays lasts 3 ms on two
/// threads, and starting a thread with a fresh stack cost the sports car 4% of it (1.87×
/// to 1.95× over one thread).
pub fn for_each_claimed<T: Send>(
    threads: Option<usize>,
    items: impl Iterator<Item = T> + Send,
    work: impl Fn(T) + Sync,
) -> Result<()> {
    let threads = match threads {
        Some(n) => n.max(1),
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let items = Mutex::new(items);
    let next = || items.lock().unwrap_or_else(|e| e.into_inner()).next();
    let worker = || {
        while let Some(item) = next() {
            work(item);
        }
    };
    if threads == 1 {
        worker();
        return Ok(());
    }
    let pool = thread_pool(Some(threads - 1))?;
    pool.in_place_scope(|s| {
        for _ in 1..threads {
            s.spawn(|_| worker());
        }
        worker();
    });
    Ok(())
}

/// `work` of every item, in the items' order, scheduled as [`for_each_claimed`].
pub fn map_claimed<T: Sync, R: Send>(
    threads: Option<usize>,
    items: &[T],
    work: impl Fn(&T) -> R + Sync,
) -> Result<Vec<R>> {
    let mut out: Vec<Option<R>> = Vec::with_capacity(items.len());
    out.resize_with(items.len(), || None);
    for_each_claimed(threads, out.iter_mut().zip(items), |(slot, item)| *slot = Some(work(item)))?;
    // Every slot is written: each pair is claimed exactly once and the scope waits for all.
    // (Sequentially: a parallel pass here started rayon's global pool for a frame's
    // thousand-odd moves.)
    Ok(out.into_iter().map(|r| r.expect("every item was claimed")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_pool_per_thread_count() {
        let a = thread_pool(Some(2)).unwrap();
        let b = thread_pool(Some(2)).unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(a.current_num_threads(), 2);
        let c = thread_pool(Some(3)).unwrap();
        assert_eq!(c.current_num_threads(), 3);
        assert!(!Arc::ptr_eq(&a, &c));
        // Zero asks for one worker, as before.
        assert_eq!(thread_pool(Some(0)).unwrap().current_num_threads(), 1);
    }

    #[test]
    fn every_item_once_in_order() {
        for threads in [Some(1), Some(2), Some(5), None] {
            let items: Vec<u64> = (0..1000).collect();
            let got = map_claimed(threads, &items, |&x| x * x).unwrap();
            assert_eq!(got, items.iter().map(|x| x * x).collect::<Vec<_>>());
            let sum = std::sync::atomic::AtomicU64::new(0);
            for_each_claimed(threads, items.iter(), |&x| {
                sum.fetch_add(x, std::sync::atomic::Ordering::Relaxed);
            })
            .unwrap();
            assert_eq!(sum.into_inner(), 999 * 1000 / 2);
        }
    }
}

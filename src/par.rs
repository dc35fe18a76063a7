//! Data parallelism for the native build, on rayon's pool: index ranges mapped in parallel,
//! results in index order. Every item is computed by the same function of its index alone
//! (per-job state is scratch only), so the output never depends on the number of threads: plans
//! stay byte-identical across machines and equal the wasm build's. No floating-point reduction
//! runs here. Long sorts of integer keys run here too: their order is unique.
//!
//! The wasm build has no threads: everything runs inline there. Natively the pool has one thread
//! per core, or `RAYON_NUM_THREADS` (1 turns parallelism off, for single-thread figures).

/// Threads work is spread over (1 on wasm).
pub(crate) fn threads() -> usize {
    #[cfg(target_arch = "wasm32")]
    {
        1
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        rayon::current_num_threads()
    }
}

/// `f(&mut state, i)` for every `i` in `0..n`, in order; `init` makes a job's scratch `state`.
pub(crate) fn map<S, R, I, F>(n: usize, init: I, f: F) -> Vec<R>
where
    R: Send,
    I: Fn() -> S + Sync + Send,
    F: Fn(&mut S, usize) -> R + Sync + Send,
{
    #[cfg(target_arch = "wasm32")]
    {
        let mut state = init();
        (0..n).map(|i| f(&mut state, i)).collect()
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        if threads() == 1 {
            // Not even a hand-over to the pool's one thread.
            let mut state = init();
            return (0..n).map(|i| f(&mut state, i)).collect();
        }
        (0..n).into_par_iter().map_init(init, f).collect()
    }
}

/// [`map`] without per-job state: `f(i)` for every `i` in `0..n`, in order.
pub(crate) fn each<R, F>(n: usize, f: F) -> Vec<R>
where
    R: Send,
    F: Fn(usize) -> R + Sync + Send,
{
    map(n, || (), |_, i| f(i))
}

/// Like [`map`] for fallible items: the error of the lowest index that fails, as a sequential
/// loop would return it.
pub(crate) fn try_map<R, E, F>(n: usize, f: F) -> Result<Vec<R>, E>
where
    R: Send,
    E: Send,
    F: Fn(usize) -> Result<R, E> + Sync + Send,
{
    each(n, f).into_iter().collect()
}

/// The lowest `i` in `0..n` where `hit(i)` is true or fails, as a sequential loop that stops
/// there finds it (the same index, or that index's error). Items past a hit already found are
/// skipped.
pub(crate) fn find_first<E, F>(n: usize, hit: F) -> Result<Option<usize>, E>
where
    E: Send,
    F: Fn(usize) -> Result<bool, E> + Sync + Send,
{
    let stop = |(_, r): &(usize, Result<bool, E>)| !matches!(r, Ok(false));
    #[cfg(target_arch = "wasm32")]
    let first = (0..n).map(|i| (i, hit(i))).find(stop);
    #[cfg(not(target_arch = "wasm32"))]
    let first = if threads() == 1 || n < FIND_INLINE {
        (0..n).map(|i| (i, hit(i))).find(stop)
    } else {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(|i| (i, hit(i))).find_first(stop)
    };
    first.map(|(i, r)| r.map(|_| i)).transpose()
}

/// [`find_first`] runs fewer items than this inline: handing them to the pool cost more than it
/// saved on the spacing's sets of a few meridians (the 40k panel's spacing took 527–583 ms with
/// them on the pool, 506 ms inline).
#[cfg(not(target_arch = "wasm32"))]
const FIND_INLINE: usize = 8;

/// `v` sorted, on the pool when there are threads and `v` is long. Unstable: only for types
/// whose equal elements are identical (plain integer keys), so the order is the same either way.
pub(crate) fn sort_unstable<T: Ord + Send>(v: &mut [T]) {
    #[cfg(not(target_arch = "wasm32"))]
    if threads() > 1 && v.len() >= SORT_INLINE {
        use rayon::slice::ParallelSliceMut;
        return v.par_sort_unstable();
    }
    v.sort_unstable()
}

/// [`sort_unstable`] sorts fewer items than this inline.
#[cfg(not(target_arch = "wasm32"))]
const SORT_INLINE: usize = 1 << 14;

/// `(a(), b())`, side by side on the pool when there are threads.
pub(crate) fn join<A, B>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B + Send) -> (A, B)
where
    A: Send,
    B: Send,
{
    #[cfg(target_arch = "wasm32")]
    {
        (a(), b())
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        if threads() == 1 {
            return (a(), b());
        }
        rayon::join(a, b)
    }
}

/// `background()` on the pool while `foreground()` runs on this thread (both inline, one after
/// the other, on wasm and on one thread): for stages that depend on neither's result.
/// `foreground` may use what cannot cross threads (the caller's clock). The background job runs
/// on the current pool (an installed one too), like every other job here.
pub(crate) fn beside<A, B>(background: impl FnOnce() -> A + Send, foreground: impl FnOnce() -> B) -> (A, B)
where
    A: Send,
{
    #[cfg(target_arch = "wasm32")]
    {
        let b = foreground();
        (background(), b)
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        if threads() == 1 {
            let b = foreground();
            return (background(), b);
        }
        let mut a = None;
        // A panic in the background job is re-raised when the scope ends, as it would be inline.
        let b = rayon::in_place_scope(|s| {
            s.spawn(|_| a = Some(background()));
            foreground()
        });
        (a.expect("the scope ran its job"), b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_in_index_order() {
        for n in [0, 1, 63, 64, 129, 1000, 4097] {
            let got = map(
                n,
                || 0usize,
                |calls, i| {
                    *calls += 1;
                    i * i
                },
            );
            assert_eq!(got, (0..n).map(|i| i * i).collect::<Vec<_>>(), "n = {n}");
        }
    }

    #[test]
    fn beside_returns_both_results() {
        let data: Vec<u64> = (0..10_000).collect();
        let (sum, max) = beside(|| data.iter().sum::<u64>(), || data.iter().copied().max());
        assert_eq!((sum, max), (49_995_000, Some(9_999)));
    }

    #[test]
    fn try_map_returns_the_first_error_in_index_order() {
        let got = try_map(5000, |i| if i % 1000 == 999 { Err(i) } else { Ok(i) });
        assert_eq!(got, Err(999));
        assert_eq!(try_map(10, Ok::<_, ()>).unwrap().len(), 10);
    }

    #[test]
    fn find_first_finds_the_lowest_hit_or_error() {
        let hit = |i: usize| -> Result<bool, usize> {
            if i == 700 {
                return Err(i);
            }
            Ok(i % 97 == 96 && i > 300)
        };
        for n in [0, 5, 300, 400, 1000] {
            let sequential = (0..n).find_map(|i| match hit(i) {
                Ok(false) => None,
                Ok(true) => Some(Ok(i)),
                Err(e) => Some(Err(e)),
            });
            assert_eq!(find_first(n, hit), sequential.transpose(), "n = {n}");
        }
    }
}

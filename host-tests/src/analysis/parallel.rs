//! Work spread over the available cores (std threads; docs/analysis.md#speed-and-memory).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// `f(0)`, ..., `f(count - 1)` in that order, computed on the available cores (at most `count` threads, each
/// taking the next index when it is free).
pub(super) fn on_cores<T: Send>(count: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, count.max(1));
    if workers == 1 {
        return (0..count).map(f).collect();
    }
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..count).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= count {
                    break;
                }
                let value = f(i);
                if let Ok(mut r) = results.lock() {
                    r[i] = Some(value);
                }
            });
        }
    });
    results.into_inner().unwrap_or_default().into_iter().flatten().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_in_index_order() {
        let squares = on_cores(50, |i| i * i);
        assert_eq!(squares, (0..50).map(|i| i * i).collect::<Vec<_>>());
        assert!(on_cores(0, |i| i).is_empty());
    }
}

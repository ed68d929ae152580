//! Parallel checks over large per-atom arrays (a million atoms and more): the index of the
//! first item that fails a test, found without a per-item early exit so that each chunk's test
//! vectorises.

use rayon::prelude::*;

/// Items per chunk tested at once (each chunk in one thread, without early exit).
const CHUNK: usize = 1 << 14;

/// Index of the first item of `items` for which `ok` is false, or `None` when all pass.
pub fn first_failing<T: Sync>(items: &[T], ok: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    let chunk = items
        .par_chunks(CHUNK)
        .position_first(|c| !c.iter().fold(true, |all, x| all & ok(x)))?;
    let start = chunk * CHUNK;
    items[start..]
        .iter()
        .position(|x| !ok(x))
        .map(|i| start + i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_first_failure_across_chunks() {
        let mut v = vec![1.0f32; 3 * CHUNK + 5];
        assert_eq!(first_failing(&v, |x| x.is_finite()), None);
        v[3 * CHUNK + 2] = f32::NAN;
        assert_eq!(first_failing(&v, |x| x.is_finite()), Some(3 * CHUNK + 2));
        v[CHUNK + 7] = f32::INFINITY;
        v[CHUNK + 9] = f32::NAN;
        assert_eq!(first_failing(&v, |x| x.is_finite()), Some(CHUNK + 7));
        assert_eq!(first_failing::<f32>(&[], |x| x.is_finite()), None);
    }
}

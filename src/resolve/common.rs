//! What the hidden-surface workspaces share: compile-time size checks and a panic-free sort.

/// The inherent `render` of a hidden-surface workspace: `render_sized` at its full `W × H`.
/// (A macro rather than a trait method, so the workspaces keep it as an inherent method that
/// needs no import.)
macro_rules! render_whole_target {
    () => {
        /// Renders `scene`, handing each of the `H` rows to `sink` once, top to bottom.
        pub fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
            &mut self,
            scene: &Scene<'_>,
            options: &RenderOptions<SUB_BITS, C, A>,
            sink: &mut K,
        ) -> Result<FrameStats, RenderError<K::Error>> {
            self.render_sized(W, H, scene, options, sink)
        }
    };
}
pub(crate) use render_whole_target;

/// Compile-time checks shared by the workspaces.
pub(crate) const fn check_sizes(w: usize, h: usize, tris: usize) {
    assert!(
        w >= 1 && w <= crate::project::MAX_SCREEN,
        "width must be 1..=2048"
    );
    assert!(
        h >= 1 && h <= crate::project::MAX_SCREEN,
        "height must be 1..=2048"
    );
    assert!(
        tris <= crate::scene::MAX_SCENE_TRIANGLES,
        "TRIS must be at most 65535"
    );
}

/// Swaps `v[a]` and `v[b]`, which the caller knows to be in range (checked again, so that no
/// panic path remains).
pub(crate) fn swap_within<T>(v: &mut [T], a: usize, b: usize) {
    if a < v.len() && b < v.len() {
        v.swap(a, b);
    } else {
        debug_assert!(
            false,
            "internal error: swap of {a} and {b} out of {}",
            v.len()
        );
    }
}

/// Whether `v[a]`'s key is below `v[b]`'s (`false` if either is out of range).
fn key_below<T, K: Ord>(v: &[T], a: usize, b: usize, key: &mut impl FnMut(&T) -> K) -> bool {
    match (v.get(a), v.get(b)) {
        (Some(x), Some(y)) => key(x) < key(y),
        _ => false,
    }
}

/// Sorts `v` by `key`, ascending and unstably, without allocating and without a panic path:
/// insertion sort for up to 16 entries, heapsort (`O(n log n)`) beyond. (The standard
/// `sort_unstable_by_key` keeps a panic for inconsistent orders, which firmware must not link.)
pub(crate) fn sort_by_key<T, K: Ord>(v: &mut [T], mut key: impl FnMut(&T) -> K) {
    let n = v.len();
    if n <= 16 {
        for i in 1..n {
            let mut j = i;
            while j > 0 && key_below(v, j, j - 1, &mut key) {
                swap_within(v, j, j - 1);
                j -= 1;
            }
        }
        return;
    }
    // A max-heap by key, then its top moved to the end of the shrinking heap, `n − 1` times.
    let mut sift_down = |v: &mut [T], mut root: usize, end: usize| loop {
        let mut child = 2 * root + 1;
        if child >= end {
            break;
        }
        if child + 1 < end && key_below(v, child, child + 1, &mut key) {
            child += 1;
        }
        if !key_below(v, root, child, &mut key) {
            break;
        }
        swap_within(v, root, child);
        root = child;
    };
    for root in (0..n / 2).rev() {
        sift_down(v, root, n);
    }
    for end in (1..n).rev() {
        swap_within(v, 0, end);
        sift_down(v, 0, end);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[test]
    fn the_panic_free_sort_sorts_like_the_standard_one() {
        // Lengths on both sides of the switch to heapsort, with and without repeated keys.
        let mut rng = crate::test_rng::XorShift32::new(0x2545_f491_u32);
        let mut next = move || rng.next_u32();
        for len in (0..=40).chain([255, 1000]) {
            for range in [4, 1 << 20] {
                let v: Vec<(u32, usize)> = (0..len).map(|i| (next() % range, i)).collect();
                let mut ours = v.clone();
                sort_by_key(&mut ours, |p| p.0);
                let mut theirs = v.clone();
                theirs.sort_by_key(|p| p.0);
                // The same keys in order, and the same entries (unstable: ties in any order).
                assert!(ours.windows(2).all(|w| w[0].0 <= w[1].0), "{len}");
                assert_eq!(
                    ours.iter().map(|p| p.0).collect::<Vec<_>>(),
                    theirs.iter().map(|p| p.0).collect::<Vec<_>>()
                );
                ours.sort();
                theirs.sort();
                assert_eq!(ours, theirs, "{len}");
            }
        }
    }
}

//! Ray streams: the batches the stream entries take (at most [`MAX`]
//! rays, chosen by a mask of `u64` bits), and the conveniences every
//! implementation needs.
//!
//! Why 64 and a mask: a batch of 64 rays and their hit records is 11 KiB,
//! which stays in L1 with the nodes being walked (pbrt-v4 measured its CPU
//! wavefront 5–10x slower than its single-ray integrator for queues in
//! memory; small per-thread streams are what gained elsewhere: docs/design.md),
//! and a mask lets a stage skip dead paths without compacting the arrays.

/// The most rays a batch holds.
pub const MAX: usize = 64;

/// The rays of a batch of `n` that `active` asks for, in order.
#[inline]
pub fn lanes(active: u64, n: usize) -> impl Iterator<Item = usize> {
    let live = if n >= 64 {
        active
    } else {
        active & ((1u64 << n) - 1)
    };
    Bits(live)
}

/// Every ray of a batch of `n`, as a mask.
#[inline]
pub fn all(n: usize) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1u64 << n) - 1
    }
}

struct Bits(u64);

impl Iterator for Bits {
    type Item = usize;
    #[inline]
    fn next(&mut self) -> Option<usize> {
        if self.0 == 0 {
            return None;
        }
        let i = self.0.trailing_zeros() as usize;
        self.0 &= self.0 - 1;
        Some(i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_are_the_set_bits_below_the_batch_size() {
        assert_eq!(lanes(0b1011, 8).collect::<Vec<_>>(), vec![0, 1, 3]);
        assert_eq!(lanes(0b1011, 2).collect::<Vec<_>>(), vec![0, 1]);
        assert_eq!(lanes(u64::MAX, 64).count(), 64);
        assert_eq!(all(3), 0b111);
        assert_eq!(all(64), u64::MAX);
    }
}

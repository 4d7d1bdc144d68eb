//! The vector instruction set the kernels run: the widest this CPU has (detected once at
//! run time), or a narrower one a caller asks for ([`limit_to`], `spt --simd`), so that
//! the widths can be measured against each other on one machine and the binary a user
//! builds with plain `cargo build --release` still uses the machine it runs on.
//!
//! Every dispatch point (the BVH's traversal, the integrator's lanes) asks [`active`],
//! one relaxed atomic load, instead of `is_x86_feature_detected!` itself.

use std::sync::atomic::{AtomicU8, Ordering};

/// An instruction-set level, ordered from narrowest to widest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u8)]
pub enum Isa {
    /// What every CPU of the target has: SSE2 on x86_64 (4-wide trees, SSE kernels),
    /// portable code elsewhere.
    Baseline = 0,
    /// AVX2 (x86_64): 8-wide trees and eight lanes to a register.
    Avx2 = 1,
    /// AVX-512 F, VL, BW and DQ (x86_64): sixteen lanes to a register in the
    /// integrator's lanes, mask registers in the traversal.
    Avx512 = 2,
}

impl Isa {
    /// Every level, narrowest first.
    pub const ALL: [Isa; 3] = [Isa::Baseline, Isa::Avx2, Isa::Avx512];

    /// The name `spt --simd` takes and prints.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }

    fn from_u8(v: u8) -> Isa {
        match v {
            0 => Isa::Baseline,
            1 => Isa::Avx2,
            _ => Isa::Avx512,
        }
    }
}

impl std::fmt::Display for Isa {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The widest level this CPU runs (the standard library's detection, cached by it).
pub fn detected() -> Isa {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx2") {
            if has!("avx512f") && has!("avx512vl") && has!("avx512bw") && has!("avx512dq") {
                return Isa::Avx512;
            }
            return Isa::Avx2;
        }
    }
    Isa::Baseline
}

/// `UNSET` until the first [`active`] or [`limit_to`]; then the level in use.
static ACTIVE: AtomicU8 = AtomicU8::new(UNSET);
const UNSET: u8 = u8::MAX;

/// The level the kernels use now: [`detected`], unless [`limit_to`] lowered it.
#[inline]
pub fn active() -> Isa {
    let v = ACTIVE.load(Ordering::Relaxed);
    if v != UNSET {
        return Isa::from_u8(v);
    }
    let isa = detected();
    ACTIVE.store(isa as u8, Ordering::Relaxed);
    isa
}

/// Uses at most `isa` from now on (never more than the CPU has) and returns the level in
/// use. Call it before building accelerators: the BVH's width is chosen at build time
/// ([`crate::WideBvh`]), the kernels at each call. Process-wide, for measurements; the
/// default needs no call.
pub fn limit_to(isa: Isa) -> Isa {
    let level = isa.min(detected());
    ACTIVE.store(level as u8, Ordering::Relaxed);
    level
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_are_ordered_and_named_uniquely() {
        assert!(Isa::Baseline < Isa::Avx2 && Isa::Avx2 < Isa::Avx512);
        for (i, a) in Isa::ALL.iter().enumerate() {
            assert_eq!(Isa::from_u8(*a as u8), *a);
            for b in &Isa::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
            }
        }
    }

    #[test]
    fn detection_agrees_with_the_standard_library() {
        #[cfg(target_arch = "x86_64")]
        assert_eq!(detected() >= Isa::Avx2, std::arch::is_x86_feature_detected!("avx2"));
        #[cfg(not(target_arch = "x86_64"))]
        assert_eq!(detected(), Isa::Baseline);
    }
}

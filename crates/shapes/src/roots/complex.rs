//! Complex numbers in f64: just enough arithmetic for Laguerre's method.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A complex number in f64, just enough arithmetic for Laguerre's method.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    /// 0.
    pub const ZERO: Self = Self { re: 0.0, im: 0.0 };
    /// 1.
    pub const ONE: Self = Self { re: 1.0, im: 0.0 };

    /// re + i·im.
    #[inline]
    pub const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }

    /// The real number x.
    #[inline]
    pub const fn real(x: f64) -> Self {
        Self { re: x, im: 0.0 }
    }

    /// |z|, without overflow for large parts (`hypot`).
    #[inline]
    pub fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }

    /// The complex conjugate.
    #[inline]
    pub fn conj(self) -> Self {
        Self { re: self.re, im: -self.im }
    }

    /// z·s for a real s.
    #[inline]
    pub fn scale(self, s: f64) -> Self {
        Self { re: self.re * s, im: self.im * s }
    }

    /// The principal square root (re ≥ 0), computed without cancellation or overflow as
    /// in Numerical Recipes §5.5 (`csqrt`).
    pub fn sqrt(self) -> Self {
        if self.re == 0.0 && self.im == 0.0 {
            return Self::ZERO;
        }
        let x = self.re.abs();
        let y = self.im.abs();
        let w = if x >= y {
            let r = y / x;
            x.sqrt() * (0.5 * (1.0 + (1.0 + r * r).sqrt())).sqrt()
        } else {
            let r = x / y;
            y.sqrt() * (0.5 * (r + (1.0 + r * r).sqrt())).sqrt()
        };
        if self.re >= 0.0 {
            Self { re: w, im: self.im / (2.0 * w) }
        } else {
            Self { re: y / (2.0 * w), im: if self.im >= 0.0 { w } else { -w } }
        }
    }

    /// True if both parts are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

impl Add for Complex {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self { re: self.re + o.re, im: self.im + o.im }
    }
}

impl Sub for Complex {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self { re: self.re - o.re, im: self.im - o.im }
    }
}

impl Mul for Complex {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self { re: self.re * o.re - self.im * o.im, im: self.re * o.im + self.im * o.re }
    }
}

impl Div for Complex {
    type Output = Self;
    /// Smith's algorithm (1962; Numerical Recipes §5.5): scales by the larger part of the
    /// divisor to avoid overflow.
    #[inline]
    fn div(self, o: Self) -> Self {
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let den = o.re + r * o.im;
            Self { re: (self.re + r * self.im) / den, im: (self.im - r * self.re) / den }
        } else {
            let r = o.re / o.im;
            let den = o.im + r * o.re;
            Self { re: (self.re * r + self.im) / den, im: (self.im * r - self.re) / den }
        }
    }
}

impl Neg for Complex {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self { re: -self.re, im: -self.im }
    }
}

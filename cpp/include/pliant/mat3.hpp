// pliant — small 3×3 tensor algebra, header-only, host and device, fully unrolled by hand so that
// compilers keep every entry in registers and vectorize across elements.
#pragma once

#include "config.hpp"

namespace pliant {

/// General 3×3 matrix, row-major entries a[3*r + c].
template <class T>
struct Mat3 {
    T a[9];
    PLIANT_HD T operator()(int r, int c) const { return a[3 * r + c]; }
};

/// Symmetric 3×3 matrix stored as xx, yy, zz, xy, yz, xz.
template <class T>
struct Sym3 {
    T xx, yy, zz, xy, yz, xz;
};

template <class T>
PLIANT_HD Mat3<T> identity3() {
    return {{T(1), T(0), T(0), T(0), T(1), T(0), T(0), T(0), T(1)}};
}

template <class T>
PLIANT_HD T det(const Mat3<T>& F) {
    const T* a = F.a;
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

template <class T>
PLIANT_HD T det(const Sym3<T>& s) {
    return s.xx * (s.yy * s.zz - s.yz * s.yz) - s.xy * (s.xy * s.zz - s.yz * s.xz) +
           s.xz * (s.xy * s.yz - s.yy * s.xz);
}

template <class T>
PLIANT_HD T trace(const Sym3<T>& s) {
    return s.xx + s.yy + s.zz;
}

/// Inverse of a symmetric matrix whose determinant `d` is already known.
template <class T>
PLIANT_HD Sym3<T> inverse(const Sym3<T>& s, T d) {
    const T inv = T(1) / d;
    return {(s.yy * s.zz - s.yz * s.yz) * inv, (s.xx * s.zz - s.xz * s.xz) * inv,
            (s.xx * s.yy - s.xy * s.xy) * inv, (s.xz * s.yz - s.xy * s.zz) * inv,
            (s.xy * s.xz - s.xx * s.yz) * inv, (s.xy * s.yz - s.xz * s.yy) * inv};
}

/// a·A + b·B for symmetric A, B.
template <class T>
PLIANT_HD Sym3<T> axpby(T a, const Sym3<T>& A, T b, const Sym3<T>& B) {
    return {a * A.xx + b * B.xx, a * A.yy + b * B.yy, a * A.zz + b * B.zz,
            a * A.xy + b * B.xy, a * A.yz + b * B.yz, a * A.xz + b * B.xz};
}

/// a·A for symmetric A.
template <class T>
PLIANT_HD Sym3<T> scale(T a, const Sym3<T>& A) {
    return {a * A.xx, a * A.yy, a * A.zz, a * A.xy, a * A.yz, a * A.xz};
}

/// s·I + A.
template <class T>
PLIANT_HD Sym3<T> add_identity(T s, const Sym3<T>& A) {
    return {A.xx + s, A.yy + s, A.zz + s, A.xy, A.yz, A.xz};
}

/// Product F·S of a general and a symmetric matrix (first Piola–Kirchhoff P = F S).
template <class T>
PLIANT_HD Mat3<T> mul(const Mat3<T>& F, const Sym3<T>& S) {
    const T* a = F.a;
    Mat3<T> P;
    PLIANT_UNROLL
    for (int r = 0; r < 3; ++r) {
        const T f0 = a[3 * r], f1 = a[3 * r + 1], f2 = a[3 * r + 2];
        P.a[3 * r + 0] = f0 * S.xx + f1 * S.xy + f2 * S.xz;
        P.a[3 * r + 1] = f0 * S.xy + f1 * S.yy + f2 * S.yz;
        P.a[3 * r + 2] = f0 * S.xz + f1 * S.yz + f2 * S.zz;
    }
    return P;
}

/// Product S·B of a symmetric and a general matrix.
template <class T>
PLIANT_HD Mat3<T> mul_sym_left(const Sym3<T>& S, const Mat3<T>& B) {
    const T s[9] = {S.xx, S.xy, S.xz, S.xy, S.yy, S.yz, S.xz, S.yz, S.zz};
    Mat3<T> R;
    PLIANT_UNROLL
    for (int r = 0; r < 3; ++r) {
        PLIANT_UNROLL
        for (int c = 0; c < 3; ++c)
            R.a[3 * r + c] = s[3 * r] * B.a[c] + s[3 * r + 1] * B.a[3 + c] + s[3 * r + 2] * B.a[6 + c];
    }
    return R;
}

/// Symmetric part of a general matrix.
template <class T>
PLIANT_HD Sym3<T> sym(const Mat3<T>& A) {
    const T h = T(0.5);
    return {A.a[0], A.a[4], A.a[8], h * (A.a[1] + A.a[3]), h * (A.a[5] + A.a[7]), h * (A.a[2] + A.a[6])};
}

/// Product A·B of two symmetric matrices that commute (polynomials in one tensor, e.g. C⁻¹ and
/// dev E), so that A·B is symmetric: its upper triangle.
template <class T>
PLIANT_HD Sym3<T> mul_commuting(const Sym3<T>& A, const Sym3<T>& B) {
    return {A.xx * B.xx + A.xy * B.xy + A.xz * B.xz, A.xy * B.xy + A.yy * B.yy + A.yz * B.yz,
            A.xz * B.xz + A.yz * B.yz + A.zz * B.zz, A.xx * B.xy + A.xy * B.yy + A.xz * B.yz,
            A.xy * B.xz + A.yy * B.yz + A.yz * B.zz, A.xx * B.xz + A.xy * B.yz + A.xz * B.zz};
}

/// Deviator A − (tr A / 3) I.
template <class T>
PLIANT_HD Sym3<T> dev(const Sym3<T>& A) {
    return add_identity(-trace(A) / T(3), A);
}

/// Double contraction A : A of a symmetric matrix.
template <class T>
PLIANT_HD T ddot(const Sym3<T>& A) {
    return A.xx * A.xx + A.yy * A.yy + A.zz * A.zz + T(2) * (A.xy * A.xy + A.yz * A.yz + A.xz * A.xz);
}

/// ln y for y > 0 in plain arithmetic (no libm call: it vectorizes on CPUs and gives the same bits
/// on every backend). y = m 2^e with m in [√½, √2) from the bits; ln m = 2 atanh(s) =
/// 2s Σ_k s^(2k)/(2k + 1), s = (m − 1)/(m + 1), |s| ≤ 0.1716 (Abramowitz & Stegun 4.1.27 with
/// argument reduction; Muller, Elementary Functions, 2016, ch. 11). Truncation after s^(2K): relative
/// error below s_max^(2K+2)/(2K+3): K = 4 for float (1e-9), K = 9 for double (2.5e-17), under half
/// the type's epsilon; the result is within a few ulps of the correctly rounded ln y. Not for
/// y ≤ 0, infinities or denormals (J of an element that is still an element is none of these).
template <class T>
PLIANT_HD T log_plain(T y) {
    T m, e;
    if constexpr (sizeof(T) == 4) {
        const std::int32_t b = float_bits(static_cast<float>(y));
        e = static_cast<T>(((b >> 23) & 0xff) - 127);
        m = static_cast<T>(bits_float((b & 0x007fffff) | 0x3f800000));
    } else {
        const std::int64_t b = double_bits(static_cast<double>(y));
        e = static_cast<T>(((b >> 52) & 0x7ff) - 1023);
        m = static_cast<T>(bits_double((b & 0x000fffffffffffffLL) | 0x3ff0000000000000LL));
    }
    const bool high = m > T(1.4142135623730951);
    m = high ? m * T(0.5) : m;
    e = high ? e + T(1) : e;
    const T s = (m - T(1)) / (m + T(1));
    const T s2 = s * s;
    constexpr int K = sizeof(T) == 4 ? 4 : 9;
    T p = T(1) / T(2 * K + 1);
    PLIANT_UNROLL
    for (int k = K - 1; k >= 0; --k) p = T(1) / T(2 * k + 1) + s2 * p;
    return e * T(0.69314718055994530942) + T(2) * s * p;
}

/// J^(-1/3) by Newton's iteration y ← y (4 − J y³)/3 from a bit-level seed (as in the
/// fast inverse square root). Plain arithmetic only, so it vectorizes on CPUs and gives the same
/// bits on every backend; relative error below the type's epsilon for J in (1e-30, 1e30).
template <class T>
PLIANT_HD T inv_cbrt(T J) {
    const float jf = static_cast<float>(J);
    // Seed: exponent of J divided by −3 (0x54a2fa8c = 4/3 of the float exponent bias, tuned).
    T y = static_cast<T>(bits_float(0x54a2fa8c - float_bits(jf) / 3));
    constexpr int iterations = sizeof(T) == 4 ? 4 : 5;
    PLIANT_UNROLL
    for (int k = 0; k < iterations; ++k) y = y * (T(4) - J * y * y * y) * T(1.0 / 3.0);
    return y;
}

}  // namespace pliant

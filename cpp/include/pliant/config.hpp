// pliant — configuration shared by every backend.
//
// PLIANT_HD marks a function callable from host and device code: physics is written once
// (header-only, over structure-of-arrays data) and launched by the CPU (OpenMP) and CUDA backends.
#pragma once

#include <cstdint>

#if defined(__CUDACC__)
#define PLIANT_HD __host__ __device__ __forceinline__
#else
#define PLIANT_HD inline __attribute__((always_inline))
#endif

// PLIANT_KERNEL marks a kernel body, a lambda that an executor launches once per item:
// `[=] PLIANT_KERNEL (index_t i) { ... }` (a CUDA extended lambda under nvcc; on the host always
// inlined, so that the CPU executor's SIMD loop over an element block vectorizes the body).
#if defined(__CUDACC__)
#define PLIANT_KERNEL __host__ __device__
#else
#define PLIANT_KERNEL __attribute__((always_inline))
#endif

// Fully unroll a small fixed-count loop: GCC vectorizes the element loop across lanes only when no
// inner loop remains.
#if defined(__CUDACC__) || defined(__clang__)
#define PLIANT_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define PLIANT_UNROLL _Pragma("GCC unroll 16")
#else
#define PLIANT_UNROLL
#endif

// PLIANT_HOST_VECTORS: 1 where GCC's vector extensions (`vector_size`) exist, in host code built by
// GCC or Clang, not nvcc. The gathers whose values lie side by side (gather_forces, edge_gradient)
// then load and add several at once; elsewhere they run the same additions one value at a time.
// Defined as 0 on the command line, host code takes the scalar path too (a check of their bits).
#if !defined(PLIANT_HOST_VECTORS)
#if defined(__GNUC__) && !defined(__CUDACC__)
#define PLIANT_HOST_VECTORS 1
#else
#define PLIANT_HOST_VECTORS 0
#endif
#endif

namespace pliant {

using index_t = std::int32_t;

/// Lanes per element block of the AoSoA layout. 16 float32 lanes fill one AVX-512 register and
/// a 64-byte cache line; on CUDA, half a warp reads one contiguous 64-byte segment per field.
inline constexpr int kLanes = 16;

/// Reinterpret the bits of a float as an int and back (host: __builtin_bit_cast, device: intrinsics).
PLIANT_HD std::int32_t float_bits(float x) {
#if defined(__CUDA_ARCH__)
    return __float_as_int(x);
#else
    return __builtin_bit_cast(std::int32_t, x);
#endif
}
PLIANT_HD float bits_float(std::int32_t i) {
#if defined(__CUDA_ARCH__)
    return __int_as_float(i);
#else
    return __builtin_bit_cast(float, i);
#endif
}
/// The same for double and 64-bit integers.
PLIANT_HD std::int64_t double_bits(double x) {
#if defined(__CUDA_ARCH__)
    return __double_as_longlong(x);
#else
    return __builtin_bit_cast(std::int64_t, x);
#endif
}
PLIANT_HD double bits_double(std::int64_t i) {
#if defined(__CUDA_ARCH__)
    return __longlong_as_double(i);
#else
    return __builtin_bit_cast(double, i);
#endif
}

/// Atomically lowers *p to v if v is smaller (CUDA atomicMin; host: a compare-and-swap loop).
/// Used for "smallest offending index" searches, whose result does not depend on the order.
PLIANT_HD void atomic_min(int* p, int v) {
#if defined(__CUDA_ARCH__)
    atomicMin(p, v);
#else
    int cur = __atomic_load_n(p, __ATOMIC_RELAXED);
    while (v < cur && !__atomic_compare_exchange_n(p, &cur, v, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
#endif
}

/// Atomically adds v to *p and returns the value before (CUDA atomicAdd; host: a fetch-and-add).
/// Used for counts (integer sums, the same in any order) and slots whose order the result does not
/// depend on.
PLIANT_HD int atomic_add(int* p, int v) {
#if defined(__CUDA_ARCH__)
    return atomicAdd(p, v);
#else
    return __atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#endif
}

/// The same for 64-bit integers (CUDA: atomicAdd on the unsigned type, the same two's-complement
/// sum). Fixed-point sums (soft_gather) are integer sums: the same in any order.
PLIANT_HD std::int64_t atomic_add(std::int64_t* p, std::int64_t v) {
#if defined(__CUDA_ARCH__)
    return static_cast<std::int64_t>(
        atomicAdd(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(v)));
#else
    return __atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#endif
}

/// Atomically raises *p to v if v is larger (a maximum: the same in any order).
PLIANT_HD void atomic_max(std::int64_t* p, std::int64_t v) {
#if defined(__CUDA_ARCH__)
    atomicMax(reinterpret_cast<long long*>(p), static_cast<long long>(v));
#else
    std::int64_t cur = __atomic_load_n(p, __ATOMIC_RELAXED);
    while (v > cur && !__atomic_compare_exchange_n(p, &cur, v, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
#endif
}

/// One element slot's scratch in a phased launch (Dev::blocks_phased): value k at p[k · kStride].
/// On the CPU a block's lanes lie side by side (kStride = kLanes, so that each phase's SIMD loop
/// reads and writes whole vectors); on CUDA and the emulated device each thread has its own row
/// (kStride = 1, registers on CUDA).
template <class T, int kStride>
struct SlotScratch {
    T* p;
    PLIANT_HD T& operator[](int k) const { return p[k * kStride]; }
};

/// The middle phases of a phased launch (Dev::blocks_phased): phase c runs the items first[c] ..
/// first[c] + size[c] − 1 in one pass, 1 ≤ size[c] ≤ kPhaseItemsMax, the count a compile-time
/// constant K in that pass, so that its loop over the items unrolls inside the SIMD loop over the
/// slots. A phase functor `mid` has mid.template uniform<K>(b, first), what the slots of block b
/// share (computed once a block on the CPU, outside its SIMD loop), and
/// mid.template operator()<K>(uniform, b, l, s), slot l's part.
inline constexpr int kPhaseItemsMax = 4;
struct Phases {
    int n = 0;
    int first[2] = {0, 0}, size[2] = {0, 0};
};

/// f.template operator()<K>(args...) with K = k, 1 ≤ k ≤ kPhaseItemsMax (Phases).
template <class F, class... A>
PLIANT_HD void call_phase(int k, const F& f, A... args) {
    switch (k) {
        case 1:
            f.template operator()<1>(args...);
            break;
        case 2:
            f.template operator()<2>(args...);
            break;
        case 3:
            f.template operator()<3>(args...);
            break;
        default:
            f.template operator()<4>(args...);
            break;
    }
}

/// One slot's middle phase (call_phase): mid's uniform part for block b, then the slot's.
struct PhaseSlot {
    template <int K, class Mid, class S>
    PLIANT_HD void operator()(const Mid& mid, index_t b, int l, int first, S s) const {
        mid.template operator()<K>(mid.template uniform<K>(b, first), b, l, s);
    }
};

/// The threads of a team launch (each_counted_then_team) on the CPU and the emulated device: one
/// thread, which runs each loop in order, so that its sums need no atomics. CUDA's team is a block
/// (BlockTeam, device_cuda.cuh): each loop strided over its threads, sync a __syncthreads, add and
/// max atomic. Team code writes only what no other item of the same loop reads, or through add and
/// max, whose results no order changes.
struct SerialTeam {
    /// f(i) for i in [0, n).
    template <class F>
    PLIANT_HD void each(index_t n, const F& f) const {
        for (index_t i = 0; i < n; ++i) f(i);
    }
    /// Every thread's writes before it are seen by every thread after it.
    PLIANT_HD void sync() const {}
    /// f() on one thread of the team.
    template <class F>
    PLIANT_HD void one(const F& f) const {
        f();
    }
    /// *p += v; the value before.
    template <class V>
    PLIANT_HD V add(V* p, V v) const {
        const V before = *p;
        *p = before + v;
        return before;
    }
    /// *p = max(*p, v).
    PLIANT_HD void max(std::int64_t* p, std::int64_t v) const {
        if (v > *p) *p = v;
    }
};

/// A hint that *p will be read soon (host: a prefetch into the caches; device: nothing). No effect
/// on any result.
PLIANT_HD void prefetch(const void* p) {
#if defined(__CUDA_ARCH__)
    (void)p;
#else
    __builtin_prefetch(p);
#endif
}

}  // namespace pliant

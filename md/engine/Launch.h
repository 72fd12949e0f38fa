#pragma once
/// \file Launch.h
/// Launch plumbing for per-particle loops (device source; Thrust).
///
/// forEachBlocked(n, body) runs body(i) for every i in [0, n) through thrust::for_each over blocks
/// of consecutive indices. On the OpenMP backend a block is a plain loop over many particles with
/// the functor copied into locals: its pointers stay in registers (a functor called once per
/// element through thrust reloads them after every store, since stores through double* may alias
/// it) and a block can reduce what it computed before writing one value. On the CUDA backend a
/// block is one particle, i.e. one thread per particle as usual.
///
/// Per-block results (block maxima, counts) go to an array reduced afterwards over the blocks;
/// sums of integers and maxima are exact, so results do not depend on the blocking or the thread
/// count.
#include <thrust/device_vector.h>
#include <thrust/for_each.h>
#include <thrust/host_vector.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/scatter.h>

#if !defined(__CUDACC__)
#include <omp.h>
#endif

#include "common/HostDevice.h"

namespace granagg::md {

/// Indices per block: one on CUDA; on the OpenMP backend 16 blocks per thread (load balance
/// between threads whose blocks cost differently, e.g. dense clusters), at least 256.
inline int blockSizeFor(int n) {
#if defined(__CUDACC__)
  (void)n;
  return 1;
#else
  const int blocks = 16 * omp_get_max_threads();
  const int b = (n + blocks - 1) / blocks;
  return b < 256 ? 256 : b;
#endif
}
inline int blockCount(int n, int block) { return (n + block - 1) / block; }

/// body(i, acc) for i in block b; acc (a Reduction::value_type) is combined over the block and
/// stored in out[b].
template <class Body, class Reduction>
struct BlockedLoop {
  Body body;
  Reduction reduce;
  typename Reduction::value_type* out;  // one per block (may be null without a reduction)
  int n, block;
  HD void operator()(int b) const {
    const Body f = body;  // a local copy: its members are not aliased by f's stores
    typename Reduction::value_type acc = Reduction::identity();
    const int first = b * block, last = first + block < n ? first + block : n;
    for (int i = first; i < last; ++i) acc = reduce(acc, f(i));
    if (out) out[b] = acc;
  }
};

/// No reduction: body(i) returns nothing useful (NoReduction::value_type is int).
struct NoReduction {
  using value_type = int;
  HD static int identity() { return 0; }
  HD int operator()(int a, int) const { return a; }
};

/// body.range(first, last) for the index range of block b, stored in out[b]: for bodies that work
/// on a block as a whole (e.g. one loop over the neighbour entries of all its particles).
template <class Body>
struct BlockRangeLoop {
  Body body;
  typename Body::value_type* out;
  int n, block;
  HD void operator()(int b) const {
    const Body f = body;
    const int first = b * block, last = first + block < n ? first + block : n;
    out[b] = f.range(first, last);
  }
};

template <class Body>
void forEachBlockRange(int n, int block, const Body& body, typename Body::value_type* out) {
  thrust::for_each(thrust::counting_iterator<int>(0),
                   thrust::counting_iterator<int>(blockCount(n, block)),
                   BlockRangeLoop<Body>{body, out, n, block});
}

/// Combines the per-block results: a handful of values. On the OpenMP backend a plain loop on the
/// calling thread (thrust::reduce would open another parallel region, whose fork and join cost
/// more than the work); on CUDA thrust::reduce on the device.
template <class T, class Op>
T reduceBlocks(const thrust::device_vector<T>& blocks, T init, Op op) {
#if defined(__CUDACC__)
  return thrust::reduce(blocks.begin(), blocks.end(), init, op);
#else
  const T* b = thrust::raw_pointer_cast(blocks.data());
  for (std::size_t k = 0; k < blocks.size(); ++k) init = op(init, b[k]);
  return init;
#endif
}

/// Combines per-slot values (storage order) in particle-id order, sequentially on the host: the
/// same bits whatever the storage order (it changes with re-sorting and restarts), the thread
/// count or the backend. For observables (sampled every so many steps), not for per-step work:
/// it copies the values to the host.
template <class T, class Op>
T reduceById(const thrust::device_vector<T>& per_slot, const thrust::device_vector<int>& id, T init,
             Op op) {
  thrust::device_vector<T> by_id(per_slot.size());
  thrust::scatter(per_slot.begin(), per_slot.end(), id.begin(), by_id.begin());
  const thrust::host_vector<T> h = by_id;
  for (std::size_t k = 0; k < h.size(); ++k) init = op(init, h[k]);
  return init;
}

template <class Body, class Reduction>
void forEachBlocked(int n, int block, const Body& body, const Reduction& reduce,
                    typename Reduction::value_type* out) {
  thrust::for_each(thrust::counting_iterator<int>(0),
                   thrust::counting_iterator<int>(blockCount(n, block)),
                   BlockedLoop<Body, Reduction>{body, reduce, out, n, block});
}

}  // namespace granagg::md

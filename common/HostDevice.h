#pragma once
/// \file HostDevice.h
/// The HD macro marks physics functions compiled for both host and device.
/// Our own macro, because the CUDA 13 Thrust no longer defines __host__/__device__ for g++
/// (STYLE.md, "Keep CUDA-only code small"). Besides this header, only md/engine/Launch.h (the
/// block launches), md/engine/PhaseTimer.h (device synchronisation for timing), md/fft/ (cuFFT)
/// and md/engine/Engine.cpp (the device's name and the thread settings) call the CUDA API; a few
/// sources choose a CPU-only path with GRANAGG_CUDA (the SIMD pair chunks, the run log's
/// backend line).
#if defined(__CUDACC__)
#define HD __host__ __device__
#else
#define HD
#endif

/// HD_INLINE: an HD function that must be inlined into its caller's loop (g++ gives up inlining in
/// large functors, and a call in a per-particle loop costs more than the work).
#if defined(__CUDACC__)
#define HD_INLINE __host__ __device__ __forceinline__
#elif defined(__GNUC__)
#define HD_INLINE inline __attribute__((always_inline))
#else
#define HD_INLINE inline
#endif

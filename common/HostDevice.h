#pragma once
/// \file HostDevice.h
/// The HD macro marks physics functions compiled for both host and device.
/// Our own macro, because the CUDA 13 Thrust no longer defines __host__/__device__ for g++
/// (STYLE.md, "Keep CUDA-only code small"). This is the only header besides the FFT and
/// CUDA-check plumbing that knows about CUDA.
#if defined(__CUDACC__)
#define HD __host__ __device__
#else
#define HD
#endif

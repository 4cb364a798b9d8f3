// HostDevice.h - FLUIDSURF_HD marks plain functions that nvcc compiles for the host and the
// device alike (the math shared by the CPU and CUDA backends: field/FieldMath.h,
// classify/ClassRule.h); a plain C++ compiler sees nothing.
#pragma once

#ifdef __CUDACC__
#define FLUIDSURF_HD __host__ __device__
#else
#define FLUIDSURF_HD
#endif

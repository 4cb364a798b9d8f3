// Check.cuh - turn CUDA errors into fluidsurf::Error with the call and file:line.
#pragma once

#include <fluidsurf/Error.h>

#include <cuda_runtime.h>

#include <string>

#define FLUIDSURF_CUDA_CHECK(call)                                                                 \
    do {                                                                                           \
        const cudaError_t err_ = (call);                                                           \
        if (err_ != cudaSuccess)                                                                   \
            throw ::fluidsurf::Error(std::string("CUDA error: ") + #call +                         \
                                     " failed: " + cudaGetErrorString(err_) + " (" + __FILE__ +    \
                                     ":" + std::to_string(__LINE__) + ")");                        \
    } while (0)

// RequireGpu.h - skip a CUDA test, with the reason, where there is no usable GPU (CI).
#pragma once

#include "backend/Backend.h"

#include <gtest/gtest.h>

#include <string>

#define FLUIDSURF_REQUIRE_GPU()                                                                    \
    do {                                                                                           \
        std::string why;                                                                           \
        if (!fluidsurf::backend::cudaUsable(&why)) GTEST_SKIP() << "no usable GPU: " << why;       \
    } while (0)

// PackKernels.cc - which kernels repeat the one before (PackKernels.h), counted per run of words,
// then the others' entries written at their runs' offsets.
#include "backend/PackKernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>

namespace fluidsurf {
namespace backend {

PackedKernels packKernels(const field::AnisotropicKernels& table)
{
    const size_t n = table.extent.size() / 3;
    const bool weights = !table.weight.empty();
    // Kernel j's entry is the one before's when every float of it matches bit for bit.
    const auto repeats = [&](size_t j) {
        return j > 0 &&
               std::memcmp(&table.a[6 * j], &table.a[6 * (j - 1)], 6 * sizeof(float)) == 0 &&
               std::memcmp(&table.extent[3 * j], &table.extent[3 * (j - 1)], 3 * sizeof(float)) ==
                   0 &&
               (!weights ||
                std::memcmp(&table.weight[j], &table.weight[j - 1], sizeof(float)) == 0);
    };
    PackedKernels out;
    const size_t words = (n + 31) / 32;
    out.fresh.assign(words, 0);
    out.freshBefore.assign(words, 0);
    constexpr size_t kRunWords = 256; // a task's words (8,192 kernels)
    const size_t runs = (words + kRunWords - 1) / kRunWords;
    std::vector<size_t> runBefore(runs + 1, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, runs), [&](const auto& r) {
        for (size_t run = r.begin(); run != r.end(); ++run) {
            size_t count = 0;
            for (size_t w = run * kRunWords; w < std::min(words, (run + 1) * kRunWords); ++w) {
                uint32_t bits = 0;
                for (size_t j = 32 * w; j < std::min(n, 32 * w + 32); ++j)
                    if (!repeats(j)) bits |= 1u << (j & 31);
                out.fresh[w] = bits;
                count += size_t(__builtin_popcount(bits));
            }
            runBefore[run + 1] = count;
        }
    });
    for (size_t run = 0; run < runs; ++run)
        runBefore[run + 1] += runBefore[run];
    const size_t m = runBefore[runs];
    out.a.resize(6 * m), out.extent.resize(3 * m);
    if (weights) out.weight.resize(m);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, runs), [&](const auto& r) {
        for (size_t run = r.begin(); run != r.end(); ++run) {
            size_t e = runBefore[run];
            for (size_t w = run * kRunWords; w < std::min(words, (run + 1) * kRunWords); ++w) {
                out.freshBefore[w] = uint32_t(e);
                for (uint32_t b = out.fresh[w]; b; b &= b - 1, ++e) {
                    const size_t j = 32 * w + size_t(__builtin_ctz(b));
                    std::memcpy(&out.a[6 * e], &table.a[6 * j], 6 * sizeof(float));
                    std::memcpy(&out.extent[3 * e], &table.extent[3 * j], 3 * sizeof(float));
                    if (weights) out.weight[e] = table.weight[j];
                }
            }
        }
    });
    return out;
}

} // namespace backend
} // namespace fluidsurf

// MortonCodes.cu - Z-order cell codes on the GPU: the first step of the neighbour structure
// (thesis §4.2.1, "handler array" keys), one thread per particle.
#include "facade/Device.h"

#include "Check.cuh"
#include "Morton.cuh"

#include <memory>

namespace fluidsurf {
namespace cuda {

namespace {

__device__ __forceinline__ uint64_t cellOf(float p, float o, float inv)
{
    const float c = floorf((p - o) * inv);
    return uint64_t(fminf(fmaxf(c, 0.f), float((1 << 21) - 1)));
}

__global__ void mortonKernel(const float3* __restrict__ pos, size_t n, float3 origin, float inv,
                             uint64_t* __restrict__ codes)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const float3 p = pos[i];
    codes[i] = mortonKey(cellOf(p.x, origin.x, inv), cellOf(p.y, origin.y, inv),
                         cellOf(p.z, origin.z, inv));
}

struct DeviceFree
{
    void operator()(void* p) const { cudaFree(p); }
};

} // namespace

std::vector<uint64_t> mortonCodes(const Vec3f* positions, size_t count, const Vec3f& origin,
                                  float cellSize, void* streamPtr)
{
    if (!(cellSize > 0)) throw Error("mortonCodes: cell size must be positive");
    std::vector<uint64_t> codes(count);
    if (count == 0) return codes;
    cudaStream_t stream = static_cast<cudaStream_t>(streamPtr);
    void* dPos = nullptr;
    void* dCodes = nullptr;
    FLUIDSURF_CUDA_CHECK(cudaMalloc(&dPos, count * sizeof(float3)));
    std::unique_ptr<void, DeviceFree> posGuard(dPos);
    FLUIDSURF_CUDA_CHECK(cudaMalloc(&dCodes, count * sizeof(uint64_t)));
    std::unique_ptr<void, DeviceFree> codeGuard(dCodes);
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(dPos, positions, count * sizeof(float3), cudaMemcpyHostToDevice, stream));
    const unsigned block = 256;
    const unsigned grid = unsigned((count + block - 1) / block);
    mortonKernel<<<grid, block, 0, stream>>>(static_cast<const float3*>(dPos), count,
                                             make_float3(origin.x, origin.y, origin.z),
                                             1.f / cellSize, static_cast<uint64_t*>(dCodes));
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(codes.data(), dCodes, count * sizeof(uint64_t),
                                         cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    return codes;
}

} // namespace cuda
} // namespace fluidsurf

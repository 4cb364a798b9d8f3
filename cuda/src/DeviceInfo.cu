// DeviceInfo.cu - device discovery.
#include <fluidsurf/cuda/Device.h>

#include "Check.cuh"

namespace fluidsurf {
namespace cuda {

DeviceInfo queryDevice()
{
    DeviceInfo info;
    int count = 0;
    const cudaError_t err = cudaGetDeviceCount(&count);
    if (err != cudaSuccess) {
        info.reason = std::string("no usable CUDA device: ") + cudaGetErrorString(err);
        cudaGetLastError();  // clear the sticky error
        return info;
    }
    if (count == 0) {
        info.reason = "no CUDA device present";
        return info;
    }
    cudaDeviceProp prop;
    if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) {
        info.reason = "cannot query CUDA device 0";
        return info;
    }
    info.usable = true;
    info.name = prop.name;
    info.computeMajor = prop.major;
    info.computeMinor = prop.minor;
    info.memoryBytes = prop.totalGlobalMem;
    return info;
}

} // namespace cuda
} // namespace fluidsurf

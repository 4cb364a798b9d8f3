// DeviceInfo.cu - device discovery.
#include "facade/Device.h"

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
        cudaGetLastError(); // clear the sticky error
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

DeviceInfo openDevice()
{
    // Once per process: creating the context takes ~0.1-0.3 s, later calls are free.
    static const DeviceInfo opened = [] {
        DeviceInfo info = queryDevice();
        if (info.usable) {
            const cudaError_t err = cudaFree(nullptr); // forces context creation
            if (err != cudaSuccess) {
                info.usable = false;
                info.reason =
                    std::string("cannot create a CUDA context: ") + cudaGetErrorString(err);
                cudaGetLastError();
            }
        }
        return info;
    }();
    return opened;
}

} // namespace cuda
} // namespace fluidsurf

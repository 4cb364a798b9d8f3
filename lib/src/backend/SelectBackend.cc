// SelectBackend.cc - which backend runs, in one place: Device::Cpu, Cuda (an error without a
// usable GPU) or Auto (the GPU when usable and the run large enough for it to pay; the CPU
// again, saying why, when CUDA fails mid-way).
#include "backend/Backend.h"

#include <fluidsurf/Rasterize.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>
#include <mutex>
#include <utility>

namespace fluidsurf {

namespace {

/// prepareDevice's look for the GPU, waited for by waitForDevice (and, failing that, by its
/// destructor at exit).
std::future<void>& opening()
{
    static std::future<void> f;
    return f;
}

std::once_flag openingStarted;

} // namespace

void prepareDevice(Device device)
{
    if (device == Device::Cpu) return;
    std::call_once(openingStarted, [] {
        std::future<void> f = std::async(std::launch::async, [] { backend::cudaUsable(); });
        opening() = std::move(f);
    });
}

void waitForDevice()
{
    std::future<void>& f = opening();
    if (f.valid()) f.wait();
}

double autoGpuParticles(int threads)
{
    return 1e6 * std::pow(std::max(threads, 1) / 4.0, 1.45);
}

namespace backend {

AutoDevice::AutoDevice(Context& ctx, size_t particles) : mCtx(ctx)
{
    if (ctx.device() != Device::Auto) return;
    const int threads = ctx.runThreads();
    const double run = double(particles) * double(ctx.framesInRun());
    const double pays = autoGpuParticles(threads);
    if (run >= pays) return;
    char text[200];
    if (ctx.framesInRun() > 1)
        std::snprintf(text, sizeof(text),
                      "auto: %zu frames of %.2gM particles, under the %.2gM the GPU needs to pay "
                      "at %d thread%s",
                      ctx.framesInRun(), double(particles) / 1e6, pays / 1e6, threads,
                      threads == 1 ? "" : "s");
    else
        std::snprintf(text, sizeof(text),
                      "auto: %.2gM particles, under the %.2gM the GPU needs to pay at %d thread%s",
                      double(particles) / 1e6, pays / 1e6, threads, threads == 1 ? "" : "s");
    mWhy = text;
    ctx.setDevice(Device::Cpu);
}

AutoDevice::~AutoDevice()
{
    if (!mWhy.empty()) mCtx.setDevice(Device::Auto);
}

void runOn(Device device, bool gpuUsable, const std::string& gpuReason, std::string& ranOn,
           const std::function<void(Backend&)>& work, const std::function<void()>& fallingBack)
{
    if (device == Device::Cuda && !gpuUsable)
        throw Error("CUDA was requested but there is no usable GPU: " + gpuReason);
    if (device == Device::Cpu || !gpuUsable) {
        const std::unique_ptr<Backend> cpu = makeCpuBackend();
        ranOn = cpu->name();
        work(*cpu);
        return;
    }
    const std::unique_ptr<Backend> gpu = makeCudaBackend();
    try {
        ranOn = gpu->name();
        work(*gpu);
    } catch (const ValueError&) {
        throw; // the input's fault: the CPU would say the same
    } catch (const Cancelled&) {
        throw;
    } catch (const Error& e) {
        // CUDA failed (out of device memory, ...): Auto means "the GPU if it can", so the CPU
        // takes over and says why; an explicit cuda request reports the failure.
        if (device == Device::Cuda) throw;
        const std::unique_ptr<Backend> cpu = makeCpuBackend();
        ranOn = std::string("cpu (CUDA failed: ") + e.what() + ")";
        if (fallingBack) fallingBack();
        work(*cpu);
    }
}

void runOn(Device device, bool gpuUsable, const std::string& gpuReason, RasterizeStats& stats,
           const std::function<void(Backend&)>& work)
{
    runOn(
        device, gpuUsable, gpuReason, stats.device,
        [&](Backend& b) {
            work(b);
            b.deviceStats(stats); // nothing for the CPU
        },
        [&] { stats.gpuStages.clear(), stats.gpuBytes = 0; });
}

} // namespace backend
} // namespace fluidsurf

// DeviceMemory.cuh - device allocations freed on every path (exceptions included), with the
// live and peak byte counts the benchmark reports; CUDA events for stage timings.
#pragma once

#include "Check.cuh"

#include <string>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace cuda {

/// The caller's stream, or a non-blocking stream of our own (never the legacy default stream,
/// which would serialise with every other user of the device).
class Stream
{
public:
    explicit Stream(void* given)
    {
        if (given) {
            mStream = static_cast<cudaStream_t>(given);
        } else {
            FLUIDSURF_CUDA_CHECK(cudaStreamCreateWithFlags(&mStream, cudaStreamNonBlocking));
            mOwned = true;
        }
    }
    Stream(const Stream&) = delete;
    Stream& operator=(const Stream&) = delete;
    ~Stream()
    {
        if (mOwned) cudaStreamDestroy(mStream);
    }
    cudaStream_t get() const { return mStream; }

private:
    cudaStream_t mStream = nullptr;
    bool mOwned = false;
};

/// Stream-ordered (cudaMallocAsync / cudaFreeAsync): freeing a buffer while queued work still
/// reads it is safe, and nothing synchronises the device.
class DeviceMemory
{
public:
    explicit DeviceMemory(cudaStream_t stream) : mStream(stream) {}
    DeviceMemory(const DeviceMemory&) = delete;
    DeviceMemory& operator=(const DeviceMemory&) = delete;
    ~DeviceMemory()
    {
        for (const Block& b : mBlocks)
            cudaFreeAsync(b.ptr, mStream);
        cudaStreamSynchronize(mStream);
    }

    template <typename T> T* alloc(size_t count)
    {
        const size_t bytes = count ? count * sizeof(T) : 1;
        void* d = nullptr;
        FLUIDSURF_CUDA_CHECK(cudaMallocAsync(&d, bytes, mStream));
        mBlocks.push_back({d, bytes});
        mLive += bytes;
        if (mLive > mPeak) mPeak = mLive;
        return static_cast<T*>(d);
    }

    template <typename T> T* upload(const T* host, size_t count)
    {
        T* d = alloc<T>(count);
        if (count)
            FLUIDSURF_CUDA_CHECK(
                cudaMemcpyAsync(d, host, count * sizeof(T), cudaMemcpyHostToDevice, mStream));
        return d;
    }

    /// Free one allocation once the work queued so far is done.
    void release(const void* p)
    {
        for (size_t i = 0; i < mBlocks.size(); ++i)
            if (mBlocks[i].ptr == p) {
                FLUIDSURF_CUDA_CHECK(cudaFreeAsync(mBlocks[i].ptr, mStream));
                mLive -= mBlocks[i].bytes;
                mBlocks.erase(mBlocks.begin() + long(i));
                return;
            }
    }

    size_t liveBytes() const { return mLive; }
    size_t peakBytes() const { return mPeak; }

private:
    struct Block
    {
        void* ptr;
        size_t bytes;
    };
    cudaStream_t mStream;
    std::vector<Block> mBlocks;
    size_t mLive = 0, mPeak = 0;
};

/// Runs a CUB device algorithm the two-phase way: call(nullptr, bytes) sizes its scratch, then
/// call(scratch, bytes) runs it; the scratch is freed once the queued work is done.
template <typename Call> void runCub(DeviceMemory& mem, Call&& call)
{
    size_t bytes = 0;
    FLUIDSURF_CUDA_CHECK(call(nullptr, bytes));
    void* scratch = mem.alloc<char>(bytes);
    FLUIDSURF_CUDA_CHECK(call(scratch, bytes));
    mem.release(scratch);
}

/// Named points on a stream; stage i lasts from mark i-1 to mark i (CUDA events, so GPU time).
class StageEvents
{
public:
    explicit StageEvents(cudaStream_t stream) : mStream(stream) { mark(""); }
    StageEvents(const StageEvents&) = delete;
    StageEvents& operator=(const StageEvents&) = delete;
    ~StageEvents()
    {
        for (auto& e : mEvents)
            cudaEventDestroy(e.second);
    }
    void mark(const char* name)
    {
        cudaEvent_t e;
        FLUIDSURF_CUDA_CHECK(cudaEventCreate(&e));
        mEvents.emplace_back(name, e);
        FLUIDSURF_CUDA_CHECK(cudaEventRecord(e, mStream));
    }
    /// (name, milliseconds) per stage; waits for the last mark.
    std::vector<std::pair<std::string, double>> stages() const
    {
        std::vector<std::pair<std::string, double>> out;
        FLUIDSURF_CUDA_CHECK(cudaEventSynchronize(mEvents.back().second));
        for (size_t i = 1; i < mEvents.size(); ++i) {
            float ms = 0;
            FLUIDSURF_CUDA_CHECK(
                cudaEventElapsedTime(&ms, mEvents[i - 1].second, mEvents[i].second));
            out.emplace_back(mEvents[i].first, double(ms));
        }
        return out;
    }

private:
    cudaStream_t mStream;
    std::vector<std::pair<std::string, cudaEvent_t>> mEvents;
};

} // namespace cuda
} // namespace fluidsurf

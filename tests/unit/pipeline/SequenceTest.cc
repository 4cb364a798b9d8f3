// SequenceTest.cc - runFrameStages: every frame through read, make and write in that order,
// write in frame order, never two frames in one slot, the stages overlapping when slots allow
// it (and not with one slot), and the first exception stopping the run.
#include <fluidsurf/Sequence.h>

#include <gtest/gtest.h>

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace fluidsurf {
namespace {

/// What the stages saw, checked as they run: each slot's frame from its read to its write.
struct Log
{
    std::mutex mutex;
    std::vector<size_t> read, made, written;
    std::vector<long> slotFrame; ///< -1: free
    std::vector<int> stage;      ///< per frame: 0 none, 1 read, 2 made, 3 written
    bool clash = false, outOfOrder = false;

    Log(size_t frames, size_t slots) : slotFrame(slots, -1), stage(frames, 0) {}

    FrameStages stages()
    {
        FrameStages s;
        s.read = [this](size_t k, size_t slot) {
            std::lock_guard<std::mutex> lock(mutex);
            clash |= slotFrame[slot] != -1 || slot != k % slotFrame.size();
            slotFrame[slot] = long(k);
            outOfOrder |= stage[k] != 0;
            stage[k] = 1, read.push_back(k);
        };
        s.make = [this](size_t k, size_t slot) {
            std::lock_guard<std::mutex> lock(mutex);
            clash |= slotFrame[slot] != long(k);
            outOfOrder |= stage[k] != 1;
            stage[k] = 2, made.push_back(k);
        };
        s.write = [this](size_t k, size_t slot) {
            std::lock_guard<std::mutex> lock(mutex);
            clash |= slotFrame[slot] != long(k);
            slotFrame[slot] = -1;
            outOfOrder |= stage[k] != 2;
            stage[k] = 3, written.push_back(k);
        };
        return s;
    }
};

std::vector<size_t> upTo(size_t n)
{
    std::vector<size_t> v(n);
    for (size_t i = 0; i < n; ++i)
        v[i] = i;
    return v;
}

TEST(Sequence, EveryFrameGoesThroughItsStagesInOrderAndWriteSeesTheFramesInOrder)
{
    for (size_t slots : {1, 2, 3, 4, 7}) {
        Log log(40, slots);
        FrameStages s = log.stages();
        const FrameStages inner = s;
        // some work inside the stages, parallel where make may be
        s.make = [&](size_t k, size_t slot) {
            std::this_thread::sleep_for(std::chrono::microseconds(200 * (k % 3)));
            inner.make(k, slot);
        };
        runFrameStages(40, s, slots);
        EXPECT_FALSE(log.clash) << slots << " slots";
        EXPECT_FALSE(log.outOfOrder) << slots << " slots";
        EXPECT_EQ(log.read, upTo(40)) << slots << " slots";
        EXPECT_EQ(log.written, upTo(40)) << slots << " slots";
        if (slots <= 3) EXPECT_EQ(log.made, upTo(40)) << slots << " slots: make in order";
        EXPECT_EQ(log.made.size(), 40u);
    }
    Log none(1, 3);
    runFrameStages(0, none.stages(), 3);
    EXPECT_TRUE(none.read.empty());
}

/// Make of frame 0 waits (at most 3 s) for the read of frame 1: it ends early only when the
/// two run at once. Returns whether they did.
bool readOverlapsMake(size_t slots)
{
    std::mutex m;
    std::condition_variable cv;
    bool readOne = false;
    FrameStages s;
    s.read = [&](size_t k, size_t) {
        if (k != 1) return;
        std::lock_guard<std::mutex> lock(m);
        readOne = true;
        cv.notify_all();
    };
    s.make = [&](size_t k, size_t) {
        if (k != 0) return;
        std::unique_lock<std::mutex> lock(m);
        cv.wait_for(lock, std::chrono::seconds(3), [&] { return readOne; });
    };
    bool overlapped = false;
    s.write = [&](size_t k, size_t) {
        if (k != 0) return;
        std::lock_guard<std::mutex> lock(m);
        overlapped = readOne; // frame 1 was read before frame 0 left make
    };
    runFrameStages(3, s, slots);
    return overlapped;
}

TEST(Sequence, FrameKPlusOneIsReadWhileFrameKIsMadeUnlessThereIsOneSlot)
{
    if (tbb::info::default_concurrency() < 2) GTEST_SKIP() << "one hardware thread: no overlap";
    EXPECT_TRUE(readOverlapsMake(2));
    EXPECT_TRUE(readOverlapsMake(3));
    EXPECT_FALSE(readOverlapsMake(1));
}

TEST(Sequence, TheFirstExceptionStopsTheRunAndNoLaterFrameIsWritten)
{
    for (size_t slots : {1, 3, 5}) {
        Log log(30, slots);
        FrameStages s = log.stages();
        const FrameStages inner = s;
        s.make = [&](size_t k, size_t slot) {
            if (k == 4) throw std::runtime_error("frame 4 is bad");
            inner.make(k, slot);
        };
        try {
            runFrameStages(30, s, slots);
            ADD_FAILURE() << "no exception with " << slots << " slots";
        } catch (const std::runtime_error& e) {
            EXPECT_STREQ(e.what(), "frame 4 is bad");
        }
        for (size_t k : log.written)
            EXPECT_LT(k, 4u) << slots << " slots";
        EXPECT_LE(log.read.size(), 4 + slots) << "reading stops within the frames in flight";
        EXPECT_FALSE(log.clash);
    }
}

TEST(Sequence, AFailureDoesNotCutShortTheParallelLoopsOfAStageUnderWay)
{
    if (tbb::info::default_concurrency() < 2) GTEST_SKIP() << "one hardware thread: no overlap";
    // Frame 1's make starts; frame 0's write waits for that, then throws; then frame 1's make
    // runs a parallel loop: every one of its iterations must run.
    const size_t n = 200000;
    std::mutex m;
    std::condition_variable cv;
    bool started = false, thrown = false;
    std::atomic<size_t> iterations{0};
    FrameStages s;
    s.read = [](size_t, size_t) {};
    s.make = [&](size_t k, size_t) {
        if (k != 1) return;
        {
            std::unique_lock<std::mutex> lock(m);
            started = true;
            cv.notify_all();
            cv.wait_for(lock, std::chrono::seconds(3), [&] { return thrown; });
        }
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64),
                          [&](const tbb::blocked_range<size_t>& r) {
                              std::this_thread::sleep_for(std::chrono::microseconds(5));
                              iterations += r.size();
                          });
    };
    s.write = [&](size_t k, size_t) {
        if (k != 0) return;
        {
            std::unique_lock<std::mutex> lock(m);
            cv.wait_for(lock, std::chrono::seconds(3), [&] { return started; });
            thrown = true;
        }
        cv.notify_all();
        throw std::runtime_error("frame 0 cannot be written");
    };
    EXPECT_THROW(runFrameStages(4, s, 3), std::runtime_error);
    ASSERT_TRUE(started) << "frame 1 was not made while frame 0 was written";
    EXPECT_EQ(iterations, n);
}

} // namespace
} // namespace fluidsurf

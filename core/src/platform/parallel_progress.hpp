// parallel_progress.hpp - run independent work items over TBB threads while the calling thread
// reports progress and handles cancellation (progress.hpp).
//
// Internal to libdqjulia. The renderer runs image tiles through it, the baker slabs of a grid.
// The calling thread only waits and calls the user's callback (at the start, a few times a
// second and once with 1.0 at the end), so a host such as Blender sees the callback on the thread that asked
// for the work. Cost: one extra thread per call; the items themselves run on TBB's pool. Where
// the system refuses that thread (the user's process limit, an address-space cap), the calling
// thread runs items too and reports between them, so the work goes on with the threads there are.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dqjulia/progress.hpp"

namespace dqj {

/// Windows: TBB ends its scheduler, joining its worker threads, when the last thread that used it
/// exits. Each call below runs the work from a thread of its own, so that would happen at the end
/// of every call, inside that thread's exit; with the MinGW build that wait never ends (seen under
/// Wine: every render or bake with a callback hung; likely the loader lock thread exits hold).
/// An arena kept for the life of the process keeps the scheduler, so no thread exit ends it.
/// Elsewhere the scheduler ends and restarts safely, and nothing is kept.
inline void keepSchedulerAlive() {
#ifdef _WIN32
    static tbb::task_arena* const kept = [] {
        auto* arena = new tbb::task_arena();  // never deleted: the process's exit ends its threads
        arena->initialize();
        return arena;
    }();
    (void)kept;
#endif
}

/// One work item. `stop` becomes true when the user cancelled or another item failed;
/// long items should poll it and return early (short ones may ignore it: items not yet
/// started are skipped anyway).
using WorkItem = std::function<void(std::size_t index, const std::atomic<bool>& stop)>;

/// Runs work(index) for every index in [0, count) in parallel. With a callback, it is called
/// with 0.0 before any work starts, with the fraction of items done about every 100 ms, and
/// with 1.0 at the end. If it returns
/// false, the remaining items are skipped and Cancelled is thrown once all threads are idle.
/// The first exception thrown by an item (or by the callback) is rethrown on the calling thread.
inline void parallelForWithProgress(std::size_t count, const ProgressCallback& progress, const WorkItem& work) {
    std::atomic<bool> stop{false};
    std::atomic<std::size_t> done{0};
    std::mutex errorMutex;
    std::exception_ptr error;

    // Items never throw into TBB: the first failure is kept and the rest are skipped. `afterItem`
    // runs on the thread that ran the item, after it. TBB itself may still throw (memory for its
    // own tasks refused): kept as an item's failure is, since on the worker thread an exception
    // leaving would terminate the process.
    auto keep = [&] {
        std::lock_guard<std::mutex> lock(errorMutex);
        if (!error) error = std::current_exception();
        stop = true;
    };
    auto runItems = [&](const std::function<void()>& afterItem) {
        try {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t index = range.begin(); index != range.end(); ++index) {
                                      if (stop.load(std::memory_order_relaxed)) return;
                                      try {
                                          work(index, stop);
                                          done.fetch_add(1, std::memory_order_relaxed);
                                          if (afterItem) afterItem();
                                      } catch (...) {
                                          keep();
                                      }
                                  }
                              });
        } catch (...) {
            keep();
        }
    };

    if (!progress) {
        runItems({});
        if (error) std::rethrow_exception(error);
        return;
    }

    if (!progress(0.0)) throw Cancelled();  // lets a caller cancel even work shorter than 100 ms
    keepSchedulerAlive();

    std::mutex mutex;
    std::condition_variable finishedSignal;
    bool finished = false;
    std::optional<std::thread> worker;
    try {
        worker.emplace([&] {
            runItems({});
            {
                std::lock_guard<std::mutex> lock(mutex);
                finished = true;
            }
            finishedSignal.notify_one();
        });
    } catch (const std::system_error&) {
        // No thread to spare: this thread runs items too, and calls the callback (on itself, as
        // promised) after one of its items when 100 ms have passed.
        const std::thread::id caller = std::this_thread::get_id();
        auto last = std::chrono::steady_clock::now();
        bool cancelled = false;
        runItems([&] {
            if (std::this_thread::get_id() != caller || cancelled) return;  // `cancelled`: the caller's alone
            const auto now = std::chrono::steady_clock::now();
            if (now - last < std::chrono::milliseconds(100)) return;
            last = now;
            if (!progress(static_cast<double>(done.load()) / static_cast<double>(count))) {
                cancelled = true;
                stop = true;
            }
        });
        if (error) std::rethrow_exception(error);
        if (cancelled) throw Cancelled();
        progress(1.0);
        return;
    }
    // The worker must be joined on every path, or std::thread's destructor terminates.
    struct Joiner {
        std::thread& thread;
        std::atomic<bool>& stop;
        ~Joiner() {
            if (thread.joinable()) {
                stop = true;
                thread.join();
            }
        }
    } joiner{*worker, stop};

    bool cancelled = false;
    {
        std::unique_lock<std::mutex> lock(mutex);
        while (!finished) {
            if (finishedSignal.wait_for(lock, std::chrono::milliseconds(100), [&] { return finished; })) break;
            if (cancelled) continue;  // only waiting for running items to return
            lock.unlock();
            const double fraction = count ? static_cast<double>(done.load()) / static_cast<double>(count) : 1.0;
            const bool keepGoing = progress(fraction);  // if it throws, Joiner stops and joins
            lock.lock();
            if (!keepGoing) {
                cancelled = true;
                stop = true;
            }
        }
    }
    worker->join();
    if (error) std::rethrow_exception(error);
    if (cancelled) throw Cancelled();
    progress(1.0);  // the work is complete: a late "false" has nothing left to cancel
}

}  // namespace dqj

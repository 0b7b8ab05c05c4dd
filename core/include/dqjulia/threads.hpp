// dqjulia/threads.hpp - how many threads the core's parallel work (TBB, OpenVDB's tools) may
// use, so a farm task stays within the CPUs its scheduler gave it. Cost: nothing while no
// work runs; a ThreadLimit is one tbb::global_control.
#pragma once

#include <memory>

#include "dqjulia/export.h"

namespace dqj {

/// The threads a task should use: SLURM_CPUS_PER_TASK when it is set (a Slurm job step),
/// else the CPUs this process may run on (sched_getaffinity: a cgroup's cpuset, taskset,
/// a scheduler's binding), else every hardware thread.
DQJ_API int defaultThreadCount();

/// The most threads a command lets a task ask for (--threads, --cpus-per-task).
inline constexpr int kMaxThreadCount = 4096;

/// While it lives, the core's parallel work uses at most `threads` threads (at least 1).
class DQJ_API ThreadLimit {
public:
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;

private:
    struct Control;
    std::unique_ptr<Control> control_;
};

}  // namespace dqj

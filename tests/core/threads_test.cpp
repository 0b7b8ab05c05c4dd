// The threads a farm task uses (threads.hpp): SLURM_CPUS_PER_TASK when Slurm sets it, else
// the CPUs the process may run on; ThreadLimit caps TBB while it lives.
#include <gtest/gtest.h>

#include <sched.h>
#include <stdlib.h>

#include <tbb/global_control.h>

#include "dqjulia/threads.hpp"

namespace {

int affinityCount() {
    cpu_set_t set;
    CPU_ZERO(&set);
    EXPECT_EQ(::sched_getaffinity(0, sizeof set, &set), 0);
    return CPU_COUNT(&set);
}

TEST(Threads, TheDefaultIsTheSchedulersAllotment) {
    ::unsetenv("SLURM_CPUS_PER_TASK");
    EXPECT_EQ(dqj::defaultThreadCount(), affinityCount());
    ::setenv("SLURM_CPUS_PER_TASK", "3", 1);
    EXPECT_EQ(dqj::defaultThreadCount(), 3);
    for (const char* bad : {"", "0", "two", "4x", "-1"}) {
        ::setenv("SLURM_CPUS_PER_TASK", bad, 1);
        EXPECT_EQ(dqj::defaultThreadCount(), affinityCount()) << bad;
    }
    ::unsetenv("SLURM_CPUS_PER_TASK");
}

TEST(Threads, ALimitHoldsWhileItLives) {
    const auto parallelism = [] {
        return tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    };
    const std::size_t before = parallelism();
    {
        const dqj::ThreadLimit limit(1);
        EXPECT_EQ(parallelism(), 1u);
    }
    EXPECT_EQ(parallelism(), before);
}

}  // namespace

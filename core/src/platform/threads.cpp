// The thread count of the core's parallel work (threads.hpp).
#include "dqjulia/threads.hpp"

#ifdef _WIN32
#include <windows.h>
#else
#include <sched.h>
#endif

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

#include <tbb/global_control.h>

namespace dqj {

struct ThreadLimit::Control {
    explicit Control(int threads) : control(tbb::global_control::max_allowed_parallelism, std::size_t(threads)) {}
    tbb::global_control control;
};

int defaultThreadCount() {
    if (const char* slurm = std::getenv("SLURM_CPUS_PER_TASK")) {
        char* end = nullptr;
        const long count = std::strtol(slurm, &end, 10);
        if (end != slurm && *end == '\0' && count >= 1 && count <= 65536) return int(count);
    }
#ifdef _WIN32
    DWORD_PTR process = 0, system = 0;
    if (::GetProcessAffinityMask(::GetCurrentProcess(), &process, &system) && process != 0) {
        int count = 0;
        for (; process; process &= process - 1) ++count;
        return count;
    }
#else
    cpu_set_t set;
    CPU_ZERO(&set);
    if (::sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
#endif
    return int(std::max(1u, std::thread::hardware_concurrency()));
}

ThreadLimit::ThreadLimit(int threads) : control_(std::make_unique<Control>(std::max(1, threads))) {}

ThreadLimit::~ThreadLimit() = default;

}  // namespace dqj

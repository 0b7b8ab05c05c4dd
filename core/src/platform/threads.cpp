// The thread count of the core's parallel work (threads.hpp).
#include "dqjulia/threads.hpp"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

#include <tbb/global_control.h>

#include "platform/platform.hpp"

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
    if (const int count = platform::processorCount(); count > 0) return count;
    return int(std::max(1u, std::thread::hardware_concurrency()));
}

ThreadLimit::ThreadLimit(int threads) : control_(std::make_unique<Control>(std::max(1, threads))) {}

ThreadLimit::~ThreadLimit() = default;

}  // namespace dqj

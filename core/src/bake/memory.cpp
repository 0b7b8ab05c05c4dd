// The memory a bake, a mesh or a merge may take and is estimated to take (memory.hpp,
// bake.hpp): the estimates per sampled leaf, the process's limits and headroom, the peak it used.
#include "bake/memory.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <optional>
#include <string>

#ifdef _WIN32
#include <windows.h>
#define PSAPI_VERSION 2  // GetProcessMemoryInfo from kernel32.dll, not psapi.dll
#include <psapi.h>
#else
#include <sys/resource.h>
#include <unistd.h>
#endif

#include "files/text_input.hpp"

namespace dqj {

/// Memory per sampled 8^3 leaf beyond the sampled leaf itself: the rebuild's mesh and distance
/// grids, the level set, the fog volume; attribute grids on top. Measured on the default
/// fractal (peak RSS minus the 65 MB of a tiny bake, over sampled leaves: 4.3 kB at 256^3,
/// 5.2 kB at 512^3, 4.9 kB at 1024^3) and doubled for headroom. With the colour grid (its
/// seeds, their propagation and the grid) 7.7 kB at 512^3 and 9.8 kB at 1024^3 in all, so
/// about 5 kB more, doubled (the sweeps it replaced took 17 kB: 4.2 GB at 1024^3, above the
/// 12 kB this allowed).
MemoryModel bakeMemoryModel(const BakeSettings& bake) {
    MemoryModel model;
    model.fixedBytes = 96.0 * 1024 * 1024;
    model.bytesPerLeaf = 9.0 * 1024;
    if (hasGrid(bake, BakeGrid::Color)) model.bytesPerLeaf += 10.0 * 1024;
    if (hasGrid(bake, BakeGrid::Trap)) model.bytesPerLeaf += 4.0 * 1024;
    if (hasGrid(bake, BakeGrid::Iterations)) model.bytesPerLeaf += 4.0 * 1024;
    return model;
}

/// Memory per sampled 8^3 leaf beyond the sampled leaf itself: volumeToMesh's masks and polygon
/// pools, and the mesh's arrays. Measured on the default fractal (peak RSS minus the 65 MB of a
/// tiny mesh, over sampled leaves: 3.0 kB at 256^3, 5.6 kB at 512^3) and doubled for headroom.
MemoryModel meshMemoryModel() {
    MemoryModel model;
    model.fixedBytes = 96.0 * 1024 * 1024;
    model.bytesPerLeaf = 10.0 * 1024;
    return model;
}

MemoryLimitError::MemoryLimitError(const std::string& message, std::uint64_t estimate, std::uint64_t limit)
    : ParamError("bake.resolution", "bake.resolution: " + message), estimate_(estimate), limit_(limit) {}

#ifdef _WIN32

// Windows: the limits a job object puts on this process and on its job (what ulimit and cgroups are
// on Linux; the job's less its peak use), and half of the physical memory available.
std::uint64_t processMemoryHeadroom() {
    JOBOBJECT_EXTENDED_LIMIT_INFORMATION job{};
    if (!::QueryInformationJobObject(nullptr, JobObjectExtendedLimitInformation, &job, sizeof job, nullptr))
        return UINT64_MAX;  // not in a job
    std::uint64_t result = UINT64_MAX;
    const DWORD flags = job.BasicLimitInformation.LimitFlags;
    if (flags & JOB_OBJECT_LIMIT_PROCESS_MEMORY) result = std::min<std::uint64_t>(result, job.ProcessMemoryLimit);
    if (flags & JOB_OBJECT_LIMIT_JOB_MEMORY)
        result = std::min<std::uint64_t>(result, job.JobMemoryLimit > job.PeakJobMemoryUsed
                                                     ? job.JobMemoryLimit - job.PeakJobMemoryUsed
                                                     : 0);
    return result;
}

std::uint64_t defaultMemoryLimit() {
    MEMORYSTATUSEX status{};
    status.dwLength = sizeof status;
    const std::uint64_t half = ::GlobalMemoryStatusEx(&status) ? status.ullAvailPhys / 2 : std::uint64_t(1) << 31;
    return std::min(half, processMemoryHeadroom());
}

#else

namespace {

/// The number a file holds ("max", no number and missing files: nullopt; a read error throws).
std::optional<std::uint64_t> readNumberFile(const std::string& path) {
    const std::optional<std::string> text = lineStartingWith(path, "");
    if (!text || text->empty() || !std::isdigit(static_cast<unsigned char>(text->front()))) return std::nullopt;
    return std::strtoull(text->c_str(), nullptr, 10);
}

/// "VmSize:  123 kB" from /proc/self/status, in bytes.
std::uint64_t statusBytes(const std::string& key) {
    const std::optional<std::string> value = lineStartingWith("/proc/self/status", key);
    return value ? std::strtoull(value->c_str(), nullptr, 10) * 1024 : 0;
}

std::uint64_t headroom(std::uint64_t limit, std::uint64_t used) { return limit > used ? limit - used : 0; }

}  // namespace

std::uint64_t processMemoryHeadroom() {
    std::uint64_t result = UINT64_MAX;
    struct rlimit limit {};
    if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
        result = std::min(result, headroom(limit.rlim_cur, statusBytes("VmSize:")));
    if (::getrlimit(RLIMIT_DATA, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
        result = std::min(result, headroom(limit.rlim_cur, statusBytes("VmData:")));
    // Every cgroup from ours up to the root may cap us ("0::/a/b" for v2, "N:memory:/a/b" for v1).
    const std::string cgroups = readSmallFile("/proc/self/cgroup", std::size_t(1) << 20).value_or("");
    for (std::size_t start = 0, end = 0; start < cgroups.size(); start = end + 1) {
        end = std::min(cgroups.find('\n', start), cgroups.size());
        const std::string line = cgroups.substr(start, end - start);
        const std::size_t first = line.find(':'), second = line.find(':', first + 1);
        if (first == std::string::npos || second == std::string::npos) continue;
        const std::string controllers = line.substr(first + 1, second - first - 1);
        std::string group = line.substr(second + 1);
        const bool v2 = controllers.empty();
        if (!v2 && controllers.find("memory") == std::string::npos) continue;
        const std::string root = v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory";
        for (;;) {
            const std::string folder = root + (group == "/" ? "" : group);
            const auto max = readNumberFile(folder + (v2 ? "/memory.max" : "/memory.limit_in_bytes"));
            const auto used = readNumberFile(folder + (v2 ? "/memory.current" : "/memory.usage_in_bytes"));
            if (max && *max < (std::uint64_t(1) << 60)) result = std::min(result, headroom(*max, used.value_or(0)));
            if (group.empty() || group == "/") break;
            const std::size_t slash = group.rfind('/');
            group = slash == 0 || slash == std::string::npos ? "/" : group.substr(0, slash);
        }
    }
    return result;
}

std::uint64_t defaultMemoryLimit() {
    const std::optional<std::string> available = lineStartingWith("/proc/meminfo", "MemAvailable:");
    std::uint64_t half = available ? std::strtoull(available->c_str(), nullptr, 10) * 1024 / 2 : 0;
    if (half == 0) {
        const long pages = ::sysconf(_SC_AVPHYS_PAGES);
        const long pageSize = ::sysconf(_SC_PAGESIZE);
        half = pages > 0 && pageSize > 0 ? std::uint64_t(pages) * std::uint64_t(pageSize) / 2 : std::uint64_t(1) << 31;
    }
    return std::min(half, processMemoryHeadroom());
}

#endif

std::uint64_t peakMemoryBytes() {
#ifdef _WIN32
    PROCESS_MEMORY_COUNTERS counters{};
    return ::GetProcessMemoryInfo(::GetCurrentProcess(), &counters, sizeof counters) ? counters.PeakWorkingSetSize : 0;
#else
    rusage usage{};
    ::getrusage(RUSAGE_SELF, &usage);
    return std::uint64_t(usage.ru_maxrss) * 1024;
#endif
}

std::string formatBytes(std::uint64_t bytes) {
    char text[32];
    const double value = double(bytes);
    if (value >= 1e9)
        std::snprintf(text, sizeof text, "%.1f GB", value / 1e9);
    else if (value >= 1e6)
        std::snprintf(text, sizeof text, "%.0f MB", value / 1e6);
    else
        std::snprintf(text, sizeof text, "%.0f kB", value / 1e3);
    return text;
}

}  // namespace dqj

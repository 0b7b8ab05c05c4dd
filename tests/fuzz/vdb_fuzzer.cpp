// libFuzzer target: reading a VDB file back (`render --voxels`), the path a truncated or
// damaged bake takes. Any input must give an image or a std::exception with a message, never
// a crash, a huge allocation (libFuzzer's -rss_limit_mb / -malloc_limit_mb) or a sanitizer report.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <string>

#include "voxel_render.hpp"  // core/cli: the command's voxel renderer reads VDB files back

// OpenVDB sizes some buffers from the file (a damaged compressed chunk may claim petabytes).
// Outside sanitizers such a request fails in malloc and operator new throws std::bad_alloc,
// which readDensity reports; AddressSanitizer's operator new aborts instead. So this program
// (only this fuzzer) has an operator new that fails as glibc's would for sizes no bake holds.
namespace {
constexpr std::size_t kLargestAllocation = std::size_t(1) << 31;
void* allocate(std::size_t size) {
    if (size >= kLargestAllocation) throw std::bad_alloc();  // libFuzzer stops at 2 GB itself
    if (void* memory = std::malloc(size ? size : 1)) return memory;
    throw std::bad_alloc();
}
}  // namespace
void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* memory) noexcept { std::free(memory); }
void operator delete[](void* memory) noexcept { std::free(memory); }
void operator delete(void* memory, std::size_t) noexcept { std::free(memory); }
void operator delete[](void* memory, std::size_t) noexcept { std::free(memory); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    return size >= kLargestAllocation ? nullptr : std::malloc(size ? size : 1);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void operator delete(void* memory, const std::nothrow_t&) noexcept { std::free(memory); }
void operator delete[](void* memory, const std::nothrow_t&) noexcept { std::free(memory); }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string path = [] {
        char name[] = "/tmp/dqjulia_vdb_fuzz_XXXXXX";
        const int fd = ::mkstemp(name);
        if (fd < 0) std::abort();
        ::close(fd);
        return std::string(name);
    }();
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file || std::fwrite(data, 1, size, file) != size || std::fclose(file) != 0) std::abort();
    dqj::Params params;
    params.render.width = 8;
    params.render.height = 8;
    params.render.samples = 1;
    try {
        dqj::renderVoxels(params, path);
    } catch (const std::exception& error) {
        if (error.what()[0] == '\0') std::abort();
    }
    return 0;
}

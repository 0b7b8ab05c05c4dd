// libFuzzer target: reading a VDB file back (`render --voxels`), the path a truncated or
// damaged bake takes. Any input must give an image or a std::exception with a message, never
// a crash, a huge allocation (libFuzzer's -rss_limit_mb / -malloc_limit_mb) or a sanitizer report.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "dqjulia/voxel_render.hpp"

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

// libFuzzer target: the parameter-file parser, through the C ABI as a host would call it.
// Any input must give DQJ_OK or DQJ_ERROR_PARAMETERS with a message, never a crash, a hang
// or a sanitizer report; an accepted document must round-trip.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "dqjulia/dqjulia.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static dqj_context context = [] {
        dqj_context created = nullptr;
        if (dqj_context_create(&created) != DQJ_OK) std::abort();
        return created;
    }();
    const std::string text(reinterpret_cast<const char*>(data), size);  // NUL-terminated copy
    const dqj_status status = dqj_context_set_params_json(context, text.c_str());
    if (status != DQJ_OK) {
        if (status != DQJ_ERROR_PARAMETERS || dqj_context_error(context)[0] == '\0') std::abort();
        return 0;
    }
    // Accepted: what we write back must be read back the same.
    std::size_t needed = 0;
    if (dqj_context_get_params_json(context, nullptr, 0, &needed) != DQJ_OK) std::abort();
    std::vector<char> first(needed);
    if (dqj_context_get_params_json(context, first.data(), first.size(), nullptr) != DQJ_OK) std::abort();
    if (dqj_context_set_params_json(context, first.data()) != DQJ_OK) std::abort();
    std::vector<char> second(needed);
    if (dqj_context_get_params_json(context, second.data(), second.size(), nullptr) != DQJ_OK) std::abort();
    if (first != second) std::abort();
    return 0;
}

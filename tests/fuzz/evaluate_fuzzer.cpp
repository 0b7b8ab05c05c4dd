// libFuzzer target: the evaluation entry points with arbitrary doubles (NaN, inf, huge,
// denormal), arbitrary constants, variants, iteration counts and bailouts. Everything must be
// either rejected with a status or evaluated, never crash; escape counts stay in [0, N].
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "dqjulia/dqjulia.h"

namespace {

/// Reads the next value of type T from the input, or zero when it runs out.
template <typename T>
T take(const std::uint8_t*& data, std::size_t& size) {
    T value{};
    const std::size_t count = size < sizeof(T) ? size : sizeof(T);
    std::memcpy(&value, data, count);
    data += count;
    size -= count;
    return value;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static dqj_context context = [] {
        dqj_context created = nullptr;
        if (dqj_context_create(&created) != DQJ_OK) std::abort();
        return created;
    }();
    double constant[8];
    for (double& value : constant) value = take<double>(data, size);
    const int variant = take<std::uint8_t>(data, size) % 4;  // 3 is invalid on purpose
    const int iterations = static_cast<int>(take<std::uint16_t>(data, size) % 300) - 10;
    const double bailout = take<double>(data, size);
    dqj_context_set_constant(context, constant);
    dqj_context_set_variant(context, static_cast<dqj_variant>(variant));
    dqj_context_set_iterations(context, iterations);
    dqj_context_set_bailout(context, bailout);

    std::vector<double> points(size / sizeof(double));
    if (!points.empty()) std::memcpy(points.data(), data, points.size() * sizeof(double));
    const std::size_t count8 = points.size() / 8;
    const std::size_t count3 = points.size() / 3;
    std::vector<dqj_sample> out(count3 + 1);
    if (dqj_evaluate_points(context, points.data(), count8, out.data()) != DQJ_OK) std::abort();
    if (dqj_evaluate_slice_points(context, points.data(), count3, out.data()) != DQJ_OK) std::abort();
    for (std::size_t index = 0; index < count3; ++index)
        if (out[index].n < 0 || out[index].n > 100000 || out[index].de < 0.0) std::abort();
    return 0;
}

// dqjulia/progress.hpp - progress reporting and cancellation for long work (render, bake).
#pragma once

#include <functional>
#include <stdexcept>

#include "dqjulia/export.h"

namespace dqj {

/// Called with the fraction done (0..1) from the thread that started the work: once with 0
/// before it starts, a few times a second, and once with 1 at the end. Return true to go on,
/// false to cancel: the work stops promptly and throws Cancelled. The C ABI's dqj_progress_fn
/// has the same convention (non-zero goes on, 0 cancels).
using ProgressCallback = std::function<bool(double fraction)>;

class DQJ_API Cancelled : public std::runtime_error {
public:
    Cancelled() : std::runtime_error("cancelled") {}
};

}  // namespace dqj

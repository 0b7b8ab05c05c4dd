// staged_progress.hpp - one progress bar over the stages of a bake (internal to libdqjulia).
//
// Each stage gets a callback that maps its own 0..1 onto its share of the whole job, so the
// caller's callback sees one fraction that only grows, and the stage is published to the
// optional BakeMonitor. The callbacks run on the thread that asked for the bake (they are
// handed to parallelForWithProgress), so no locking is needed here.
#pragma once

#include <algorithm>

#include "dqjulia/bake.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

class StagedProgress {
public:
    StagedProgress(ProgressCallback user, BakeMonitor* monitor) : user_(std::move(user)), monitor_(monitor) {}

    /// The callback for `stage`, covering [begin, end] of the whole job. Empty when the caller
    /// gave no callback (then the work cannot be cancelled, as with render()).
    ProgressCallback stage(BakeStage stage, double begin, double end) {
        if (monitor_) monitor_->stage = stage;
        if (!user_) return {};
        return [this, begin, end](double fraction) {
            last_ = std::max(last_, begin + std::clamp(fraction, 0.0, 1.0) * (end - begin));
            return user_(last_);
        };
    }

    void countEvaluations(std::uint64_t count) {
        if (monitor_) monitor_->evaluated.fetch_add(count, std::memory_order_relaxed);
    }
    void setDense(std::uint64_t count) {
        if (monitor_) monitor_->dense = count;
    }

private:
    ProgressCallback user_;
    BakeMonitor* monitor_;
    double last_ = 0.0;
};

}  // namespace dqj

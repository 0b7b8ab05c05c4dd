// The wording of an empty result: see empty_result.hpp.
#include "dqjulia/empty_result.hpp"

namespace dqj {

std::string emptyResultMessage(EmptyResult kind, std::string_view reason, std::string_view name) {
    std::string_view subject, state, hint;
    // Without a proven or sampled reason: what usually helps for this kind of result.
    const std::string_view sparse =
        "nothing within the bounds is in the set at this resolution; try more iterations or a higher resolution";
    switch (kind) {
        case EmptyResult::Render:
            subject = "the image";
            state = "shows no surface";
            hint =
                "no ray came within the hit threshold; try more iterations, a larger detail (render.detail, "
                "--detail) or another camera";
            break;
        case EmptyResult::Bake:
            subject = "the volume";
            state = "holds no surface";
            hint = sparse;
            break;
        case EmptyResult::Mesh:
            subject = "the mesh";
            state = "holds no surface";
            hint = sparse;
            break;
        case EmptyResult::Povray:
            subject = "the scene";
            state = "has no fractal";
            hint = "no reason is known; try more iterations or another slice";
            break;
    }
    std::string message(name.empty() ? subject : name);
    message += " ";
    message += state;
    message += ": ";
    message += reason.empty() ? hint : reason;
    return message;
}

}  // namespace dqj

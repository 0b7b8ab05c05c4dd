// dqjulia/schema.hpp - every key of the parameter file described once: its type, range, label
// and help text; its default is the one of the structs in param_types.hpp.
// Code: core/src/params/schema.cpp.
//
// The reader checks each value against its field here, validate() checks a Params against the
// same fields, and schemaJson() publishes them (with the defaults) for front ends that build
// their own controls: the Blender add-on builds its properties, its document conversion and
// its panel rows from that document (dqj_params_schema_json in the C ABI, `dqjulia schema`).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "dqjulia/export.h"

namespace dqj::schema {

/// The JSON shape of a key's value.
enum class Type {
    Boolean,
    Integer,
    Number,
    String,
    Choice,     ///< one of `choices` by name
    ChoiceSet,  ///< an array of distinct choice names (bake.grids); min/max count them
    Vec3,       ///< [x, y, z], each within min..max
    Color,      ///< linear RGB [r, g, b], each within min..max
    Vec8,       ///< 8 numbers: a's s, i, j, k, then b's
    DualQuat,   ///< 8 numbers a + b eps, shown as the two quaternions a and b
    Axes,       ///< slice axes: names "a.s,a.i,a.j" or three Vec8
    AxisPair,   ///< a rotation plane: two different axis names "a.j,b.s"
    Object,     ///< a section with fields "key.*"
    List,       ///< an array of objects with fields "key[].*"; min/max count them
    ColorList,  ///< an array of colours (the palette; the item is "key[]"); min/max count them
    Animation   ///< keyframe tracks (docs/baking.md, "Animation")
};

enum Flags : std::uint32_t {
    kOptional = 1u << 0,    ///< may be absent: the core computes it (camera.position, output.format)
    kAuto = 1u << 1,        ///< an Object that may be the string "auto" instead (bounds, bake.bounds)
    kAnimatable = 1u << 2,  ///< may be keyframed in "animation"
    kImageOnly = 1u << 3    ///< used only by the core's image renderer (dqjulia render), not by bakes or previews
};

struct Choice {
    std::string_view name;  ///< as written in the file
    std::string_view label;
    std::string_view help;
};

struct Field {
    std::string_view key;  ///< dotted path; list items as "lights[].color", palette colours "material.palette[]"
    Type type;
    std::string_view label;
    std::string_view help;
    double min = 0.0, max = 0.0;  ///< the file's range: values (each component of vectors) or item counts
    bool minExclusive = false, maxExclusive = false;
    double softMin = 0.0, softMax = 0.0;  ///< the range a slider offers; min and max when equal
    std::span<const Choice> choices =
        {};  ///< Choice, ChoiceSet (the index is the C++ enum's value); Animation: interpolations
    std::uint32_t flags = 0;

    bool has(Flags flag) const { return (flags & flag) != 0; }
};

/// Every field, sections in file order, each section's keys in file order.
DQJ_API std::span<const Field> fields();
/// The field of a dotted key; list indices may be given ("lights[1].color") or not
/// ("lights[].color"). nullptr when the key is not in the format.
DQJ_API const Field* find(std::string_view key);
/// The field of a key the code knows to exist (throws std::logic_error otherwise).
DQJ_API const Field& field(std::string_view key);

/// The schema document: {"format_version": 1, "fields": [{"key", "type", "label", "help",
/// "default", "min", "max", ...}, ...]} (docs/parameter-file.md, "Parameter schema").
DQJ_API std::string schemaJson();

/// The file's name of a choice field's value: choiceName("fractal.variant", 1) = "paper-coupled".
DQJ_API std::string_view choiceName(std::string_view key, int index);
/// The index (the C++ enum's value) of a choice by its name in the file: choiceIndex(field("fractal.variant"),
/// "dual") = 2; nullopt when the field has no choice of that name. The one way from a name to an enum value:
/// the file's reader and the command's flags both take it.
DQJ_API std::optional<int> choiceIndex(const Field& field, std::string_view name);

}  // namespace dqj::schema

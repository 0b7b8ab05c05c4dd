// The parameter file's fields (schema.hpp). Ranges, labels and help are written here and only
// here; defaults are read from the structs of param_types.hpp through the file's writer.
#include "dqjulia/schema.hpp"

#include <array>
#include <stdexcept>

#include "dqjulia/param_file.hpp"
#include "params/json_text.hpp"

namespace dqj::schema {

namespace {

using json::Json;
using json::OrderedJson;

constexpr double kHuge = 1e9;  // the range of free coordinates and vectors

constexpr std::array<Choice, 3> kVariants{{
    {"paper", "Paper",
     "The paper's rule a^2 + b^2 eps: real and dual parts iterate independently; escape when |a| > R or |b| > R"},
    {"paper-coupled", "Paper, coupled", "The paper's rule with one 8-D norm for escape and distance estimate"},
    {"dual", "Dual", "The true dual-quaternion algebra a^2 + (ab + ba) eps; escape on |a|"},
}};
constexpr std::array<Choice, 3> kColorings{{
    {"solid", "Solid", "The material colour"},
    {"iterations", "Iterations", "The smooth escape count through the palette"},
    {"trap", "Orbit trap", "The orbit's closest approach to 0 through the palette"},
}};
constexpr std::array<Choice, 3> kNormals{{
    {"auto", "Auto", "Analytic for the dual variant, central differences otherwise"},
    {"central", "Central differences", "Differences of the distance estimate"},
    {"analytic", "Analytic", "Exact, from the dual part (dual variant only)"},
}};
constexpr std::array<Choice, 3> kFormats{{
    {"png8", "PNG 8-bit", "sRGB, 8 bits a channel"},
    {"png16", "PNG 16-bit", "sRGB, 16 bits a channel"},
    {"exr", "OpenEXR", "Premultiplied linear RGBA, depth and normals"},
}};
constexpr std::array<Choice, 5> kGrids{{
    {"surface", "Surface", "Narrow-band level set of the surface"},
    {"density", "Density", "Fog volume: 1 inside, 0 outside (what Blender renders)"},
    {"color", "Color", "Linear RGB from the material's colouring"},
    {"trap", "Trap", "The orbit trap value"},
    {"iterations", "Iterations", "The smooth escape count"},
}};

constexpr std::array<Choice, 2> kInterpolations{{
    {"linear", "Linear", "Straight line to the next key"},
    {"smooth", "Smooth", "Monotone cubic: smooth through the keys, never overshooting them"},
}};

constexpr std::uint32_t kAnim = kAnimatable, kImage = kImageOnly;

const Field kFields[] = {
    // key, type, label, help, min, max, minExclusive, maxExclusive, softMin, softMax, choices, flags
    {"description", Type::String, "Description", "Free text, kept on round trips (examples say what they show)"},

    {"fractal", Type::Object, "Fractal", "The constant, the rule and the iteration"},
    {"fractal.c",
     Type::DualQuat,
     "Constant",
     "The constant c = a + b eps: a's s, i, j, k (real part), then b's (dual part)",
     -100,
     100,
     false,
     false,
     -2,
     2,
     {},
     kAnim},
    {"fractal.variant", Type::Choice, "Variant", "The iteration rule", 0, 0, false, false, 0, 0, kVariants},
    {"fractal.iterations",
     Type::Integer,
     "Iterations",
     "N, the iteration count (the paper uses 6 to 15)",
     1,
     100000,
     false,
     false,
     1,
     200,
     {},
     kAnim},
    {"fractal.bailout",
     Type::Number,
     "Bailout",
     "R, at least the containment radius r_K of the constant",
     1,
     1e150,
     true,
     false,
     1,
     20,
     {},
     kAnim},

    {"slice", Type::Object, "Slice", "The 3-D slice of the 8-D space: x, y, z map to origin + x X + y Y + z Z"},
    {"slice.axes", Type::Axes, "Axes", "Where x, y and z go: axis names \"a.s,a.i,a.j\" or three 8-D vectors", -kHuge,
     kHuge, false, false, -2, 2},
    {"slice.origin", Type::Vec8, "Origin", "The 8-D point at x = y = z = 0 (a's s, i, j, k, then b's)", -kHuge, kHuge,
     false, false, -2, 2},
    {"slice.rotations", Type::List, "Rotations", "Rotations of the axes in planes of the 8-D space, applied in order",
     0, 1e6},
    {"slice.rotations[].plane", Type::AxisPair, "Plane", "The rotation turns the first axis towards the second"},
    {"slice.rotations[].degrees",
     Type::Number,
     "Degrees",
     "Angle of the rotation",
     -36000,
     36000,
     false,
     false,
     -180,
     180,
     {},
     kAnim},

    {"bounds",
     Type::Object,
     "Bounds",
     "The sphere the renderer and the preview march in: \"auto\" = the smallest sphere holding the slice's share of "
     "the containment region",
     0,
     0,
     false,
     false,
     0,
     0,
     {},
     kAuto},
    {"bounds.center", Type::Vec3, "Center", "Centre of the bounding sphere", -kHuge, kHuge, false, false, -2, 2},
    {"bounds.radius", Type::Number, "Radius", "Radius of the bounding sphere", 0, 1e6, true, false, 0, 10},

    {"camera",
     Type::Object,
     "Camera",
     "The core's pinhole camera (not the preview's: that is Blender's view)",
     0,
     0,
     false,
     false,
     0,
     0,
     {},
     kImage},
    {"camera.position",
     Type::Vec3,
     "Position",
     "Where the camera is; absent = framing the bounds from the direction",
     -kHuge,
     kHuge,
     false,
     false,
     -10,
     10,
     {},
     kOptional | kImage},
    {"camera.target",
     Type::Vec3,
     "Target",
     "What the camera looks at; absent = the centre of the bounds",
     -kHuge,
     kHuge,
     false,
     false,
     -10,
     10,
     {},
     kOptional | kImage},
    {"camera.direction",
     Type::Vec3,
     "Direction",
     "From the target towards the camera, for automatic framing",
     -kHuge,
     kHuge,
     false,
     false,
     -2,
     2,
     {},
     kImage},
    {"camera.up", Type::Vec3, "Up", "The camera's up direction", -kHuge, kHuge, false, false, -2, 2, {}, kImage},
    {"camera.fov",
     Type::Number,
     "Field of view",
     "Vertical field of view, degrees",
     0,
     170,
     true,
     true,
     0,
     170,
     {},
     kImage},

    {"lights", Type::List, "Lights", "Directional lights of the core's renderer and the preview", 0, 1e6},
    {"lights[].direction", Type::Vec3, "Direction", "Towards the light, in the slice's coordinates", -kHuge, kHuge,
     false, false, -2, 2},
    {"lights[].color", Type::Color, "Color", "Linear RGB", 0, 1000, false, false, 0, 1},
    {"lights[].intensity", Type::Number, "Intensity", "Multiplies the colour", 0, 1000, false, false, 0, 4},

    {"material", Type::Object, "Material", "Phong shading (the paper's equation), occlusion, shadows and colouring"},
    {"material.color", Type::Color, "Color", "Base colour for solid colouring (linear RGB)", 0, 1000, false, false, 0,
     1},
    {"material.coloring", Type::Choice, "Coloring", "What colours the surface", 0, 0, false, false, 0, 0, kColorings},
    {"material.palette", Type::ColorList, "Palette", "Colours the iteration and trap colourings run through", 1, 64},
    {"material.palette[]", Type::Color, "Color", "A palette colour (linear RGB)", 0, 1000, false, false, 0, 1},
    {"material.ambient", Type::Number, "Ambient", "k_a, the ambient share", 0, 100, false, false, 0, 1},
    {"material.diffuse", Type::Number, "Diffuse", "k_d, the diffuse share", 0, 100, false, false, 0, 1},
    {"material.specular", Type::Number, "Specular", "k_s, the specular share", 0, 100, false, false, 0, 1},
    {"material.shininess", Type::Number, "Shininess", "The specular exponent s", 0, 10000, false, false, 0, 200},
    {"material.occlusion",
     Type::Number,
     "Occlusion",
     "Strength of ambient occlusion from the distance estimate, 0 = off",
     0,
     1,
     false,
     false,
     0,
     1,
     {},
     kImage},
    {"material.shadows",
     Type::Boolean,
     "Shadows",
     "Soft shadows from the distance estimate",
     0,
     0,
     false,
     false,
     0,
     0,
     {},
     kImage},
    {"material.shadow_softness",
     Type::Number,
     "Shadow softness",
     "Penumbra factor k: larger = harder shadows",
     0,
     1000,
     true,
     false,
     0,
     64,
     {},
     kImage},

    {"render", Type::Object, "Render", "The core's renderer; the step settings also drive the preview"},
    {"render.width", Type::Integer, "Width", "Image width, pixels", 1, 16384, false, false, 1, 4096, {}, kImage},
    {"render.height", Type::Integer, "Height", "Image height, pixels", 1, 16384, false, false, 1, 4096, {}, kImage},
    {"render.samples",
     Type::Integer,
     "Samples",
     "Anti-aliasing: samples x samples rays a pixel",
     1,
     16,
     false,
     false,
     1,
     16,
     {},
     kImage},
    {"render.step_factor", Type::Number, "Step factor", "Fraction of the distance estimate taken a step", 0, 1, true,
     false, 0, 1},
    {"render.max_step", Type::Number, "Max step", "Largest step, in slice units", 0, 1e6, true, false, 0, 1},
    {"render.max_steps",
     Type::Integer,
     "Max steps",
     "Most steps a ray takes",
     1,
     1000000,
     false,
     false,
     1,
     2000,
     {},
     kImage},
    {"render.detail",
     Type::Number,
     "Detail",
     "Hit threshold in pixel footprints (smaller = finer)",
     0,
     1000,
     true,
     false,
     0,
     8,
     {},
     kImage},
    {"render.normals", Type::Choice, "Normals", "How surface normals are found", 0, 0, false, false, 0, 0, kNormals,
     kImage},
    {"render.background",
     Type::Object,
     "Background",
     "A vertical gradient behind the set (or one colour [r, g, b])",
     0,
     0,
     false,
     false,
     0,
     0,
     {},
     kImage},
    {"render.background.top",
     Type::Color,
     "Background top",
     "Linear RGB at the top of the image",
     0,
     1000,
     false,
     false,
     0,
     1,
     {},
     kImage},
    {"render.background.bottom",
     Type::Color,
     "Background bottom",
     "Linear RGB at the bottom of the image",
     0,
     1000,
     false,
     false,
     0,
     1,
     {},
     kImage},

    {"output", Type::Object, "Output", "The image file of dqjulia render", 0, 0, false, false, 0, 0, {}, kImage},
    {"output.path", Type::String, "Output", "The image file; .png or .exr", 0, 0, false, false, 0, 0, {}, kImage},
    {"output.format", Type::Choice, "Format", "The image format; absent = from the path's extension", 0, 0, false,
     false, 0, 0, kFormats, kOptional | kImage},

    {"bake", Type::Object, "Bake", "OpenVDB volumes and meshes"},
    {"bake.resolution", Type::Integer, "Resolution", "Voxels across the largest side of the bake bounds", 8, 16384,
     false, false, 8, 1024},
    {"bake.bounds",
     Type::Object,
     "Bake bounds",
     "The box baked: \"auto\" = the cube around the bounding sphere, clipped to the sphere",
     0,
     0,
     false,
     false,
     0,
     0,
     {},
     kAuto},
    {"bake.bounds.min", Type::Vec3, "Min", "The box's lowest corner", -1e6, 1e6, false, false, -2, 2},
    {"bake.bounds.max", Type::Vec3, "Max", "The box's highest corner", -1e6, 1e6, false, false, -2, 2},
    {"bake.band_width", Type::Number, "Band width", "Half width of the level set's narrow band, in voxels", 1, 32,
     false, false, 1, 8},
    {"bake.grids", Type::ChoiceSet, "Grids", "The grids a volume bake writes", 1, 5, false, false, 1, 5, kGrids},
    {"bake.adaptivity", Type::Number, "Adaptivity", "Mesh adaptivity: 0 = uniform quads, more = fewer faces", 0, 1},
    {"bake.max_faces", Type::Integer, "Max faces",
     "Meshes: at most this many triangles (a quad counts as two), made by the least adaptivity that meets it, every "
     "vertex within 1.5 voxels of the full mesh (docs/baking.md); 0 = no limit",
     0, 2000000000, false, false, 0, 10000000},
    {"bake.mesh_colors", Type::Boolean, "Vertex colours", "Vertex colours from the material's colouring"},
    {"bake.color_depth", Type::Number, "Colour depth",
     "How deep below the surface the colour, trap and iteration grids reach, as a fraction of the bake's largest side "
     "(at least the band); a volume's material should absorb the light within it",
     0, 1, false, false, 0, 0.1},

    {"animation", Type::Animation, "Animation",
     "Keyframes of the animatable keys: {\"fractal.c\": [{\"frame\": 1, \"value\": [...], \"interpolation\": "
     "\"smooth\"}, ...]}",
     0, 0, false, false, 0, 0, kInterpolations},
};

std::string_view typeName(Type type) {
    switch (type) {
        case Type::Boolean: return "boolean";
        case Type::Integer: return "integer";
        case Type::Number: return "number";
        case Type::String: return "string";
        case Type::Choice: return "choice";
        case Type::ChoiceSet: return "choice_set";
        case Type::Vec3: return "vec3";
        case Type::Color: return "color";
        case Type::Vec8: return "vec8";
        case Type::DualQuat: return "dual_quaternion";
        case Type::Axes: return "axes";
        case Type::AxisPair: return "axis_pair";
        case Type::Object: return "object";
        case Type::List: return "list";
        case Type::ColorList: return "color_list";
        case Type::Animation: return "animation";
    }
    return "unknown";
}

/// A Params with one default item in every list and every optional value set: where the
/// schema finds the defaults of list items and of keys that are absent by default.
Params prototype() {
    Params params;
    params.slice.rotations = {PlaneRotation{}};
    params.slice.rotations[0].first = 2;  // a.j -> b.s: a plane that leaves the default view
    params.slice.rotations[0].second = 4;
    params.bounds = Bounds{};
    params.bounds->radius = 2.0;
    params.camera.position = glm::dvec3(0.0, 0.0, 5.0);
    params.camera.target = glm::dvec3(0.0);
    params.lights = {Light{}};
    params.material.palette = {glm::dvec3(1.0)};
    params.output.format = ImageFormat::Png8;
    params.bake.bounds = Box{};
    return params;
}

/// The value at a dotted key ("lights[].color" takes the first item) in a document, or nullptr.
const Json* valueAt(const Json& document, std::string_view key) {
    const Json* node = &document;
    std::size_t start = 0;
    while (start <= key.size()) {
        std::size_t end = key.find('.', start);
        if (end == std::string_view::npos) end = key.size();
        std::string_view part = key.substr(start, end - start);
        const bool item = part.size() >= 2 && part.substr(part.size() - 2) == "[]";
        if (item) part.remove_suffix(2);
        if (!node->is_object() || !node->contains(std::string(part))) return nullptr;
        node = &(*node)[std::string(part)];
        if (item) {
            if (!node->is_array() || node->empty()) return nullptr;
            node = &(*node)[0];
        }
        start = end + 1;
    }
    return node;
}

/// "lights[2].color" -> "lights[].color".
std::string withoutIndices(std::string_view key) {
    std::string result;
    for (std::size_t index = 0; index < key.size(); ++index) {
        result += key[index];
        if (key[index] != '[') continue;
        std::size_t close = index + 1;
        while (close < key.size() && key[close] >= '0' && key[close] <= '9') ++close;
        if (close < key.size() && key[close] == ']') index = close - 1;
    }
    return result;
}

}  // namespace

std::span<const Field> fields() { return kFields; }

const Field* find(std::string_view key) {
    const std::string pattern = withoutIndices(key);
    for (const Field& field : kFields)
        if (field.key == pattern) return &field;
    return nullptr;
}

const Field& field(std::string_view key) {
    if (const Field* found = find(key)) return *found;
    throw std::logic_error("dqjulia: no schema field \"" + std::string(key) + "\"");
}

std::string_view choiceName(std::string_view key, int index) {
    const Field& choices = field(key);
    if (index < 0 || std::size_t(index) >= choices.choices.size()) return "unknown";
    return choices.choices[std::size_t(index)].name;
}

std::optional<int> choiceIndex(const Field& field, std::string_view name) {
    for (std::size_t index = 0; index < field.choices.size(); ++index)
        if (field.choices[index].name == name) return int(index);
    return std::nullopt;
}

std::string schemaJson() {
    const Json defaults = Json::parse(toJson(Params{}));
    const Json examples = Json::parse(toJson(prototype()));
    OrderedJson list = OrderedJson::array();
    for (const Field& field : kFields) {
        OrderedJson entry;
        entry["key"] = field.key;
        entry["type"] = typeName(field.type);
        entry["label"] = field.label;
        entry["help"] = field.help;
        // The default: what toJson writes for a default Params. Keys absent there (optional
        // ones, list items, the fields of an "auto" object) give the value a front end starts
        // from when the user turns them on: "initial" for optional keys and "auto" objects.
        const Json* value = valueAt(defaults, field.key);
        const Json* example = valueAt(examples, field.key);
        if (field.has(kOptional)) {
            entry["default"] = nullptr;
            if (example) entry["initial"] = *example;
        } else if (field.has(kAuto)) {
            entry["default"] = "auto";
            if (example) entry["initial"] = *example;
        } else if (field.type == Type::String) {
            entry["default"] = value ? *value : Json("");
        } else if (field.type != Type::Object && (value || example)) {
            entry["default"] = value ? *value : *example;
        }
        if (field.min != 0.0 || field.max != 0.0) {
            entry["min"] = field.min;
            entry["max"] = field.max;
            if (field.minExclusive) entry["min_exclusive"] = true;
            if (field.maxExclusive) entry["max_exclusive"] = true;
            const bool soft = field.softMin != 0.0 || field.softMax != 0.0;
            entry["soft_min"] = soft ? field.softMin : field.min;
            entry["soft_max"] = soft ? field.softMax : field.max;
        }
        if (!field.choices.empty()) {  // for the animation: the interpolations of its keys
            OrderedJson choices = OrderedJson::array();
            for (const Choice& choice : field.choices)
                choices.push_back({{"name", choice.name}, {"label", choice.label}, {"help", choice.help}});
            entry[field.type == Type::Animation ? "interpolations" : "choices"] = choices;
        }
        if (field.has(kOptional)) entry["optional"] = true;
        if (field.has(kAuto)) entry["auto"] = true;
        if (field.has(kAnimatable)) entry["animatable"] = true;
        if (field.has(kImageOnly)) entry["image_only"] = true;
        list.push_back(entry);
    }
    OrderedJson document;
    document["format_version"] = 1;
    document["fields"] = list;
    return json::compactNumberArrays(document.dump(1)) + "\n";
}

}  // namespace dqj::schema

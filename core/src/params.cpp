// The parameter file: JSON in, validated Params out, and back. Every message names the file,
// the dotted key, what was wrong and what is allowed.
#include "dqjulia/params.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "atomic_file.hpp"

namespace dqj {

ParamError::ParamError(std::string key, const std::string& message)
    : std::runtime_error(printableText(message)), key_(std::move(key)) {}

namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

constexpr int kFormatVersion = 1;

std::size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        current[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j)
            current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(previous, current);
    }
    return previous[b.size()];
}

/// The first characters of `value` as JSON, written without recursion (a value may be nested
/// as deep as the parser allows) and without serialising more than is shown.
std::string preview(const Json& value, std::size_t limit) {
    struct Frame {
        const Json* node;
        Json::const_iterator next;
    };
    std::string text;
    std::vector<Frame> stack;
    auto open = [&](const Json& node) {
        if (!node.is_structured()) {
            text += node.dump();
            return;
        }
        text += node.is_object() ? '{' : '[';
        stack.push_back({&node, node.begin()});
    };
    open(value);
    while (!stack.empty() && text.size() <= limit) {
        Frame& frame = stack.back();
        if (frame.next == frame.node->end()) {
            text += frame.node->is_object() ? '}' : ']';
            stack.pop_back();
            continue;
        }
        if (frame.next != frame.node->begin()) text += ',';
        const auto item = frame.next++;
        if (frame.node->is_object()) text += Json(item.key()).dump() + ":";
        open(*item);  // may invalidate `frame`
    }
    if (text.size() > limit) text = text.substr(0, limit - 3) + "...";
    return text;
}

std::string describe(const Json& value) { return std::string(value.type_name()) + " " + preview(value, 40); }

/// Parses JSON with the limits of the format: at most kMaxParamsDepth levels of arrays and
/// objects (deeper documents are refused before they can exhaust a stack) and no key twice in
/// one object (nlohmann keeps the last silently). Errors name the dotted path of the key.
Json parseLimited(const std::string& text, const std::string& source) {
    struct Frame {
        bool object = false;
        std::size_t elements = 0;  // arrays: elements started so far
        std::string key;           // objects: the current key
        std::set<std::string> keys;
    };
    std::vector<Frame> frames;
    auto path = [&](const std::string& last) {
        std::string result;
        for (const Frame& frame : frames) {
            if (&frame == &frames.back() && frame.object) break;
            if (frame.object)
                result += (result.empty() ? "" : ".") + frame.key;
            else if (frame.elements > 0)
                result += "[" + std::to_string(frame.elements - 1) + "]";
        }
        return result.empty() ? last : last.empty() ? result : result + "." + last;
    };
    auto elementStarts = [&] {
        if (!frames.empty() && !frames.back().object) ++frames.back().elements;
    };
    using Event = Json::parse_event_t;
    return Json::parse(text, [&](int, Event event, Json& parsed) {
        switch (event) {
            case Event::object_start:
            case Event::array_start:
                elementStarts();
                if (frames.size() >= std::size_t(kMaxParamsDepth))
                    throw ParamError("", source + ": arrays and objects nested deeper than " + std::to_string(kMaxParamsDepth) +
                                             " levels; a parameter file needs at most 4");
                frames.emplace_back();
                frames.back().object = event == Event::object_start;
                break;
            case Event::key: {
                Frame& frame = frames.back();
                frame.key = parsed.get<std::string>();
                if (!frame.keys.insert(frame.key).second) {
                    const std::string key = path(frame.key);
                    throw ParamError(key, source + ": " + key + ": duplicate key \"" + frame.key +
                                              "\" (a key may appear once in an object; the second would replace the first)");
                }
                break;
            }
            case Event::object_end:
            case Event::array_end: frames.pop_back(); break;
            case Event::value: elementStarts(); break;
        }
        return true;
    });
}

/// The shortest text that reads back as exactly `value`, so a message never shows a value
/// rounded onto its limit ("must be at most 1, got 1" for 1.0000001).
std::string formatNumber(double value) {
    char text[64];
    const auto result = std::to_chars(text, text + sizeof text, value);
    return std::string(text, result.ptr);
}

/// Walks one JSON object: reads known keys with type and range checks, then rejects any key
/// it was not asked about, suggesting the nearest known one.
class ObjectReader {
public:
    ObjectReader(const Json& node, std::string path, const std::string& source)
        : node_(node), path_(std::move(path)), source_(source) {
        if (!node_.is_object()) fail(path_, "must be an object {...}, got " + describe(node_));
    }

    [[noreturn]] void fail(const std::string& key, const std::string& message) const {
        throw ParamError(key, source_ + ": " + (key.empty() ? "" : key + ": ") + message);
    }
    std::string keyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

    /// The value at `key`, or nullptr if absent; records the key as known.
    const Json* find(const std::string& key) {
        known_.push_back(key);
        const auto it = node_.find(key);
        return it == node_.end() ? nullptr : &*it;
    }

    double number(const Json& value, const std::string& key, double low, double high, bool lowOpen = false,
                  bool highOpen = false) const {
        if (!value.is_number()) fail(key, "must be a number, got " + describe(value));
        const double x = value.get<double>();
        if (!std::isfinite(x)) fail(key, "must be a finite number");
        if (x < low || x > high || (lowOpen && x == low) || (highOpen && x == high))
            fail(key, "must be " + std::string(lowOpen ? "greater than " : "at least ") + formatNumber(low) +
                          (highOpen ? " and less than " : " and at most ") + formatNumber(high) + ", got " + formatNumber(x));
        return x;
    }

    void readNumber(const std::string& key, double& out, double low, double high, bool lowOpen = false,
                    bool highOpen = false) {
        if (const Json* value = find(key)) out = number(*value, keyPath(key), low, high, lowOpen, highOpen);
    }

    void readInteger(const std::string& key, int& out, int low, int high) {
        const Json* value = find(key);
        if (!value) return;
        if (!value->is_number_integer() && !(value->is_number_float() && std::nearbyint(value->get<double>()) == value->get<double>()))
            fail(keyPath(key), "must be a whole number, got " + describe(*value));
        const double x = value->get<double>();
        if (x < low || x > high)
            fail(keyPath(key), "must be a whole number from " + std::to_string(low) + " to " + std::to_string(high) +
                                   ", got " + formatNumber(x));
        out = static_cast<int>(x);
    }

    void readBool(const std::string& key, bool& out) {
        const Json* value = find(key);
        if (!value) return;
        if (!value->is_boolean()) fail(keyPath(key), "must be true or false, got " + describe(*value));
        out = value->get<bool>();
    }

    void readString(const std::string& key, std::string& out) {
        const Json* value = find(key);
        if (!value) return;
        if (!value->is_string()) fail(keyPath(key), "must be a string, got " + describe(*value));
        out = value->get<std::string>();
    }

    /// A fixed-length array of finite numbers, each within [low, high].
    template <std::size_t Size>
    std::array<double, Size> array(const Json& value, const std::string& key, double low = -1e9, double high = 1e9) const {
        if (!value.is_array() || value.size() != Size)
            fail(key, "must be an array of " + std::to_string(Size) + " numbers, got " + describe(value));
        std::array<double, Size> result{};
        for (std::size_t index = 0; index < Size; ++index)
            result[index] = number(value[index], key + "[" + std::to_string(index) + "]", low, high);
        return result;
    }

    glm::dvec3 vec3(const Json& value, const std::string& key, double low = -1e9, double high = 1e9) const {
        const auto a = array<3>(value, key, low, high);
        return {a[0], a[1], a[2]};
    }
    void readVec3(const std::string& key, glm::dvec3& out, double low = -1e9, double high = 1e9) {
        if (const Json* value = find(key)) out = vec3(*value, keyPath(key), low, high);
    }
    void readColor(const std::string& key, glm::dvec3& out) { readVec3(key, out, 0.0, 1000.0); }

    /// Rejects keys nobody asked for ("unknown key 'iteratons'; did you mean 'iterations'?").
    void finish() const {
        for (const auto& item : node_.items()) {
            if (std::find(known_.begin(), known_.end(), item.key()) != known_.end()) continue;
            std::string nearest;
            std::size_t best = std::string::npos;
            for (const std::string& candidate : known_) {
                const std::size_t distance = editDistance(item.key(), candidate);
                if (distance < best) {
                    best = distance;
                    nearest = candidate;
                }
            }
            std::string message = "unknown key \"" + item.key() + "\"";
            if (best <= std::max<std::size_t>(2, item.key().size() / 3)) message += "; did you mean \"" + nearest + "\"?";
            std::string allowed;
            for (const std::string& candidate : known_) allowed += (allowed.empty() ? "" : ", ") + candidate;
            fail(keyPath(item.key()), message + " (allowed here: " + allowed + ")");
        }
    }

    const std::string& path() const { return path_; }
    const std::string& source() const { return source_; }

private:
    const Json& node_;
    std::string path_;
    const std::string& source_;
    std::vector<std::string> known_;
};

template <typename Enum, std::size_t Count>
Enum parseChoice(ObjectReader& reader, const Json& value, const std::string& key,
                 const std::array<std::pair<std::string_view, Enum>, Count>& choices) {
    std::string allowed;
    for (const auto& [name, choice] : choices) allowed += (allowed.empty() ? "" : ", ") + std::string(name);
    if (!value.is_string()) reader.fail(key, "must be one of " + allowed + ", got " + describe(value));
    for (const auto& [name, choice] : choices)
        if (value.get<std::string>() == name) return choice;
    reader.fail(key, "must be one of " + allowed + ", got " + value.dump());
}

constexpr std::array<std::pair<std::string_view, Variant>, 3> kVariants{
    {{"paper", Variant::Paper}, {"paper-coupled", Variant::PaperCoupled}, {"dual", Variant::Dual}}};
constexpr std::array<std::pair<std::string_view, Coloring>, 3> kColorings{
    {{"solid", Coloring::Solid}, {"iterations", Coloring::Iterations}, {"trap", Coloring::Trap}}};
constexpr std::array<std::pair<std::string_view, NormalMethod>, 3> kNormalMethods{
    {{"auto", NormalMethod::Auto}, {"central", NormalMethod::CentralDifferences}, {"analytic", NormalMethod::Analytic}}};
constexpr std::array<std::pair<std::string_view, BakeGrid>, 5> kBakeGrids{
    {{"surface", BakeGrid::Surface}, {"density", BakeGrid::Density}, {"color", BakeGrid::Color},
     {"trap", BakeGrid::Trap}, {"iterations", BakeGrid::Iterations}}};
constexpr std::array<std::pair<std::string_view, Interpolation>, 2> kInterpolations{
    {{"linear", Interpolation::Linear}, {"smooth", Interpolation::Smooth}}};
constexpr std::array<std::pair<std::string_view, ImageFormat>, 3> kFormats{
    {{"png8", ImageFormat::Png8}, {"png16", ImageFormat::Png16}, {"exr", ImageFormat::Exr}}};

template <typename Enum, std::size_t Count>
std::string_view nameOf(Enum value, const std::array<std::pair<std::string_view, Enum>, Count>& choices) {
    for (const auto& [name, choice] : choices)
        if (choice == value) return name;
    return "unknown";
}

void readFractal(ObjectReader reader, Fractal& fractal) {
    if (const Json* value = reader.find("c")) fractal.c = toDualQuat(reader.array<8>(*value, reader.keyPath("c"), -100.0, 100.0));
    if (const Json* value = reader.find("variant"))
        fractal.variant = parseChoice(reader, *value, reader.keyPath("variant"), kVariants);
    reader.readInteger("iterations", fractal.iterations, 1, 100000);
    reader.readNumber("bailout", fractal.bailout, 1.0, 1e150, true);
    reader.finish();
}

Vec8 readVec8(const ObjectReader& reader, const Json& value, const std::string& key) {
    const auto a = reader.array<8>(value, key);
    Vec8 v;
    std::copy(a.begin(), a.end(), v.begin());
    return v;
}

void readSlice(ObjectReader reader, SliceSpec& slice) {
    if (const Json* value = reader.find("axes")) {
        const std::string key = reader.keyPath("axes");
        if (value->is_string()) {
            try {
                const Vec8 origin = slice.base.origin;
                slice.base = sliceFromAxisNames(value->get<std::string>());
                slice.base.origin = origin;
            } catch (const std::invalid_argument& error) {
                reader.fail(key, error.what());
            }
        } else if (value->is_array() && value->size() == 3) {
            for (std::size_t axis = 0; axis < 3; ++axis)
                slice.base.axes[axis] = readVec8(reader, (*value)[axis], key + "[" + std::to_string(axis) + "]");
        } else {
            reader.fail(key, "must be axis names like \"a.s,a.i,a.j\" or an array of three 8-number vectors, got " +
                                 describe(*value));
        }
    }
    if (const Json* value = reader.find("origin")) slice.base.origin = readVec8(reader, *value, reader.keyPath("origin"));
    if (const Json* value = reader.find("rotations")) {
        const std::string key = reader.keyPath("rotations");
        if (!value->is_array()) reader.fail(key, "must be an array of {\"plane\": \"a.j,b.s\", \"degrees\": 30}, got " + describe(*value));
        slice.rotations.clear();
        for (std::size_t index = 0; index < value->size(); ++index) {
            ObjectReader item((*value)[index], key + "[" + std::to_string(index) + "]", reader.source());
            PlaneRotation rotation;
            std::string plane;
            item.readString("plane", plane);
            const std::size_t comma = plane.find(',');
            const auto first = parseAxisName(plane.substr(0, comma));
            const auto second = comma == std::string::npos ? std::nullopt : parseAxisName(plane.substr(comma + 1));
            if (!first || !second || *first == *second)
                item.fail(item.keyPath("plane"), "must name two different axes like \"a.j,b.s\" (axes: a.s a.i a.j a.k b.s b.i b.j b.k), got \"" + plane + "\"");
            rotation.first = *first;
            rotation.second = *second;
            item.readNumber("degrees", rotation.degrees, -36000.0, 36000.0);
            item.finish();
            slice.rotations.push_back(rotation);
        }
    }
    reader.finish();
}

void readBounds(ObjectReader reader, std::optional<Bounds>& bounds) {
    Bounds result;
    reader.readVec3("center", result.center);
    reader.readNumber("radius", result.radius, 0.0, 1e6, true);
    reader.finish();
    bounds = result;
}

void readCamera(ObjectReader reader, Camera& camera) {
    if (const Json* value = reader.find("position")) camera.position = reader.vec3(*value, reader.keyPath("position"));
    if (const Json* value = reader.find("target")) camera.target = reader.vec3(*value, reader.keyPath("target"));
    reader.readVec3("direction", camera.direction);
    reader.readVec3("up", camera.up);
    reader.readNumber("fov", camera.fovDegrees, 0.0, 170.0, true, true);  // as validate(): (0, 170)
    reader.finish();
}

void readLights(ObjectReader& parent, const Json& value, std::vector<Light>& lights) {
    const std::string key = parent.keyPath("lights");
    if (!value.is_array()) parent.fail(key, "must be an array of lights {\"direction\", \"color\", \"intensity\"}, got " + describe(value));
    lights.clear();
    for (std::size_t index = 0; index < value.size(); ++index) {
        ObjectReader reader(value[index], key + "[" + std::to_string(index) + "]", parent.source());
        Light light;
        reader.readVec3("direction", light.direction);
        reader.readColor("color", light.color);
        reader.readNumber("intensity", light.intensity, 0.0, 1000.0);
        reader.finish();
        lights.push_back(light);
    }
}

void readMaterial(ObjectReader reader, Material& material) {
    reader.readColor("color", material.color);
    if (const Json* value = reader.find("coloring"))
        material.coloring = parseChoice(reader, *value, reader.keyPath("coloring"), kColorings);
    if (const Json* value = reader.find("palette")) {
        const std::string key = reader.keyPath("palette");
        if (!value->is_array() || value->empty() || value->size() > 64)
            reader.fail(key, "must be an array of 1 to 64 colours [r, g, b], got " + describe(*value));
        material.palette.clear();
        for (std::size_t index = 0; index < value->size(); ++index)
            material.palette.push_back(reader.vec3((*value)[index], key + "[" + std::to_string(index) + "]", 0.0, 1000.0));
    }
    reader.readNumber("ambient", material.ambient, 0.0, 100.0);
    reader.readNumber("diffuse", material.diffuse, 0.0, 100.0);
    reader.readNumber("specular", material.specular, 0.0, 100.0);
    reader.readNumber("shininess", material.shininess, 0.0, 10000.0);
    reader.readNumber("occlusion", material.occlusion, 0.0, 1.0);
    reader.readBool("shadows", material.shadows);
    reader.readNumber("shadow_softness", material.shadowSoftness, 0.0, 1000.0, true);
    reader.finish();
}

void readRender(ObjectReader reader, RenderSettings& render) {
    reader.readInteger("width", render.width, 1, 16384);
    reader.readInteger("height", render.height, 1, 16384);
    reader.readInteger("samples", render.samples, 1, 16);
    reader.readNumber("step_factor", render.stepFactor, 0.0, 1.0, true);
    reader.readNumber("max_step", render.maxStep, 0.0, 1e6, true);
    reader.readInteger("max_steps", render.maxSteps, 1, 1000000);
    reader.readNumber("detail", render.detail, 0.0, 1000.0, true);
    if (const Json* value = reader.find("normals"))
        render.normals = parseChoice(reader, *value, reader.keyPath("normals"), kNormalMethods);
    if (const Json* value = reader.find("background")) {
        const std::string key = reader.keyPath("background");
        if (value->is_array()) {
            render.backgroundTop = render.backgroundBottom = reader.vec3(*value, key, 0.0, 1000.0);
        } else {
            ObjectReader background(*value, key, reader.source());
            background.readColor("top", render.backgroundTop);
            background.readColor("bottom", render.backgroundBottom);
            background.finish();
        }
    }
    reader.finish();
}

void readBake(ObjectReader reader, BakeSettings& bake) {
    reader.readInteger("resolution", bake.resolution, 8, 16384);
    if (const Json* value = reader.find("bounds")) {
        if (value->is_string() && value->get<std::string>() == "auto") {
            bake.bounds.reset();
        } else {
            ObjectReader box(*value, reader.keyPath("bounds"), reader.source());
            Box result;
            const Json* min = box.find("min");
            const Json* max = box.find("max");
            if (!min || !max) box.fail(box.path(), "must be \"auto\" or {\"min\": [x, y, z], \"max\": [x, y, z]}");
            result.min = box.vec3(*min, box.keyPath("min"), -1e6, 1e6);
            result.max = box.vec3(*max, box.keyPath("max"), -1e6, 1e6);
            box.finish();
            bake.bounds = result;
        }
    }
    reader.readNumber("band_width", bake.bandWidth, 1.0, 32.0);
    if (const Json* value = reader.find("grids")) {
        const std::string key = reader.keyPath("grids");
        if (!value->is_array() || value->empty())
            reader.fail(key, "must be a non-empty array of grid names (surface, density, color, trap, iterations), got " +
                                 describe(*value));
        bake.grids.clear();
        for (std::size_t index = 0; index < value->size(); ++index) {
            const BakeGrid grid = parseChoice(reader, (*value)[index], key + "[" + std::to_string(index) + "]", kBakeGrids);
            if (std::find(bake.grids.begin(), bake.grids.end(), grid) != bake.grids.end())
                reader.fail(key, "names \"" + std::string(nameOf(grid, kBakeGrids)) + "\" twice");
            bake.grids.push_back(grid);
        }
    }
    reader.readNumber("adaptivity", bake.adaptivity, 0.0, 1.0);
    reader.readBool("mesh_colors", bake.meshColors);
    reader.finish();
}

/// "slice.rotations[3].degrees" -> 3; std::nullopt for anything else.
std::optional<int> rotationTrackIndex(const std::string& key) {
    const std::string prefix = "slice.rotations[", suffix = "].degrees";
    if (key.size() <= prefix.size() + suffix.size() || key.rfind(prefix, 0) != 0 ||
        key.compare(key.size() - suffix.size(), suffix.size(), suffix) != 0)
        return std::nullopt;
    const std::string digits = key.substr(prefix.size(), key.size() - prefix.size() - suffix.size());
    if (digits.empty() || digits.size() > 4 || !std::all_of(digits.begin(), digits.end(), [](unsigned char ch) { return std::isdigit(ch); }))
        return std::nullopt;
    return std::stoi(digits);
}

/// The "animation" object: {"fractal.c": [{"frame": 1, "value": [...], "interpolation": "smooth"}, ...], ...}.
void readAnimation(const Json& node, const std::string& source, std::vector<Track>& tracks) {
    ObjectReader reader(node, "animation", source);  // checks that it is an object
    tracks.clear();
    for (const auto& item : node.items()) {
        const std::string key = reader.keyPath(item.key());
        Track track;
        double low = 0.0, high = 0.0;
        if (item.key() == "fractal.c") {
            track.target = AnimatedValue::Constant;
            low = -100.0, high = 100.0;
        } else if (item.key() == "fractal.iterations") {
            track.target = AnimatedValue::Iterations;
            low = 1.0, high = 100000.0;
        } else if (item.key() == "fractal.bailout") {
            track.target = AnimatedValue::Bailout;
            low = 1.0, high = 1e150;
        } else if (const auto rotation = rotationTrackIndex(item.key())) {
            track.target = AnimatedValue::RotationDegrees;
            track.rotation = *rotation;
            low = -36000.0, high = 36000.0;
        } else {
            reader.fail(key, "cannot be animated (animatable: fractal.c, fractal.iterations, fractal.bailout, "
                             "slice.rotations[i].degrees)");
        }
        const Json& keys = item.value();
        if (!keys.is_array() || keys.empty())
            reader.fail(key, "must be a non-empty array of keys {\"frame\": 1, \"value\": ..., \"interpolation\": \"linear\"}, got " +
                                 describe(keys));
        for (std::size_t index = 0; index < keys.size(); ++index) {
            ObjectReader keyReader(keys[index], key + "[" + std::to_string(index) + "]", source);
            Keyframe keyframe;
            const Json* frame = keyReader.find("frame");
            const Json* value = keyReader.find("value");
            if (!frame || !value) keyReader.fail(keyReader.path(), "needs \"frame\" and \"value\"");
            keyframe.frame = keyReader.number(*frame, keyReader.keyPath("frame"), -1e6, 1e6);
            if (track.target == AnimatedValue::Constant) {
                const auto c = keyReader.array<8>(*value, keyReader.keyPath("value"), low, high);
                keyframe.value.assign(c.begin(), c.end());
            } else {
                const double number = keyReader.number(*value, keyReader.keyPath("value"), low, high);
                if (track.target == AnimatedValue::Iterations && std::nearbyint(number) != number)
                    keyReader.fail(keyReader.keyPath("value"), "must be a whole number, got " + formatNumber(number));
                if (track.target == AnimatedValue::Bailout && number == low)
                    keyReader.fail(keyReader.keyPath("value"), "must be greater than 1");
                keyframe.value = {number};
            }
            if (const Json* interpolation = keyReader.find("interpolation"))
                keyframe.interpolation = parseChoice(keyReader, *interpolation, keyReader.keyPath("interpolation"), kInterpolations);
            keyReader.finish();
            if (!track.keys.empty() && !(keyframe.frame > track.keys.back().frame))
                keyReader.fail(keyReader.keyPath("frame"), "frames must increase from key to key: " + formatNumber(keyframe.frame) +
                                                               " follows " + formatNumber(track.keys.back().frame));
            track.keys.push_back(keyframe);
        }
        tracks.push_back(track);
    }
}

void readOutput(ObjectReader reader, OutputSettings& output) {
    reader.readString("path", output.path);
    if (const Json* value = reader.find("format")) output.format = parseChoice(reader, *value, reader.keyPath("format"), kFormats);
    reader.finish();
}

/// "line 3, column 5" for a byte offset into the text.
std::string lineAndColumn(const std::string& text, std::size_t offset) {
    std::size_t line = 1, column = 1;
    for (std::size_t index = 0; index < std::min(offset, text.size()); ++index) {
        if (text[index] == '\n') {
            ++line;
            column = 1;
        } else {
            ++column;
        }
    }
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

OrderedJson vec3Json(const glm::dvec3& v) { return OrderedJson::array({v.x, v.y, v.z}); }
OrderedJson vec8Json(const Vec8& v) { return OrderedJson(std::vector<double>(v.begin(), v.end())); }

/// Puts innermost arrays of numbers (vectors, colours) on one line: "[\n  1.0,\n  2.0\n]" -> "[1.0, 2.0]".
/// Strings are copied untouched.
std::string compactNumberArrays(const std::string& text) {
    std::string result;
    result.reserve(text.size());
    bool inString = false;
    for (std::size_t index = 0; index < text.size(); ++index) {
        const char ch = text[index];
        if (inString || ch != '[') {
            if (ch == '"' && (!inString || text[index - 1] != '\\')) inString = !inString;
            result += ch;
            continue;
        }
        const std::size_t close = text.find_first_of("[]{\"", index + 1);
        if (close == std::string::npos || text[close] != ']') {
            result += ch;
            continue;
        }
        result += '[';
        for (std::size_t inner = index + 1; inner < close; ++inner) {
            if (text[inner] == '\n' || text[inner] == ' ') continue;
            result += text[inner];
            if (text[inner] == ',') result += ' ';
        }
        result += ']';
        index = close;
    }
    return result;
}

bool parallel(const glm::dvec3& a, const glm::dvec3& b) {
    return glm::length(glm::cross(glm::normalize(a), glm::normalize(b))) < 1e-6;
}

}  // namespace

Params parseParams(const std::string& jsonText, const std::string& source, Validation validation) {
    if (jsonText.size() > kMaxParamsBytes)
        throw ParamError("", source + ": the document has more than " + std::to_string(kMaxParamsBytes >> 20) +
                                 " MiB; a parameter file is a few kilobytes");
    Json document;
    try {
        document = parseLimited(jsonText, source);
    } catch (const Json::parse_error& error) {
        std::string reason = error.what();
        const std::size_t colon = reason.find(": ");  // drop "[json.exception.parse_error.101] parse error at ...: "
        if (colon != std::string::npos) reason = reason.substr(colon + 2);
        throw ParamError("", source + ": " + lineAndColumn(jsonText, error.byte == 0 ? 0 : error.byte - 1) +
                                 ": malformed JSON: " + reason);
    } catch (const Json::exception& error) {  // e.g. "number overflow parsing '1e999'"
        std::string reason = error.what();
        const std::size_t bracket = reason.find("] ");
        if (bracket != std::string::npos) reason = reason.substr(bracket + 2);
        throw ParamError("", source + ": malformed JSON: " + reason);
    }
    Params params;
    ObjectReader root(document, "", source);
    if (const Json* value = root.find("version")) {
        if (!value->is_number_integer() || value->get<int>() != kFormatVersion)
            root.fail("version", "this dqjulia reads parameter format version " + std::to_string(kFormatVersion) +
                                     ", got " + describe(*value));
    }
    root.readString("description", params.description);
    if (const Json* value = root.find("fractal")) readFractal(ObjectReader(*value, "fractal", source), params.fractal);
    if (const Json* value = root.find("slice")) readSlice(ObjectReader(*value, "slice", source), params.slice);
    if (const Json* value = root.find("bounds")) {
        if (!(value->is_string() && value->get<std::string>() == "auto"))
            readBounds(ObjectReader(*value, "bounds", source), params.bounds);
    }
    if (const Json* value = root.find("camera")) readCamera(ObjectReader(*value, "camera", source), params.camera);
    if (const Json* value = root.find("lights")) readLights(root, *value, params.lights);
    if (const Json* value = root.find("material")) readMaterial(ObjectReader(*value, "material", source), params.material);
    if (const Json* value = root.find("render")) readRender(ObjectReader(*value, "render", source), params.render);
    if (const Json* value = root.find("output")) readOutput(ObjectReader(*value, "output", source), params.output);
    if (const Json* value = root.find("bake")) readBake(ObjectReader(*value, "bake", source), params.bake);
    if (const Json* value = root.find("animation")) readAnimation(*value, source, params.animation);
    root.finish();
    if (validation == Validation::TypesOnly) return params;
    try {
        validate(params);
    } catch (const ParamError& error) {
        throw ParamError(error.key(), source + ": " + error.what());
    }
    return params;
}

Params loadParams(const std::string& path, Validation validation) {
    auto fail = [&](const std::string& reason) { return ParamError("", "cannot read parameter file '" + path + "': " + reason); };
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw fail(std::strerror(errno));
    // Read at most one byte beyond the limit, so a never-ending file (/dev/zero, a stalled
    // pipe's writer) cannot grow the buffer without bound. A signal (Ctrl-C) ends the read.
    std::string text;
    char chunk[65536];
    int error = 0;
    while (text.size() <= kMaxParamsBytes) {
        const ssize_t got = ::read(fd, chunk, sizeof chunk);
        if (got < 0) error = errno;
        if (got <= 0) break;
        text.append(chunk, std::size_t(got));
    }
    ::close(fd);
    if (error == EINTR) throw fail("interrupted");
    if (error) throw fail(std::strerror(error));
    if (text.size() > kMaxParamsBytes)
        throw fail("larger than " + std::to_string(kMaxParamsBytes >> 20) + " MiB; a parameter file is a few kilobytes");
    return parseParams(text, path, validation);
}

void validate(const Params& params) {
    auto fail = [](const std::string& key, const std::string& message) { throw ParamError(key, key + ": " + message); };
    const Fractal& fractal = params.fractal;
    // The ranges here are the parameter file's, so whatever passes (from flags or the C ABI)
    // is written by --save-params as a file that reads back.
    for (int index = 0; index < 8; ++index)
        if (!(std::abs(component(fractal.c, index)) <= 100.0))
            fail("fractal.c", "every component must be a finite number from -100 to 100");
    if (fractal.iterations < 1 || fractal.iterations > 100000) fail("fractal.iterations", "must be from 1 to 100000");
    if (!(fractal.bailout > 1.0 && fractal.bailout <= 1e150))
        fail("fractal.bailout", "must be a finite number greater than 1 and at most 1e150, got " + formatNumber(fractal.bailout));
    const double needed = minimumBailout(fractal);
    if (!(fractal.bailout >= needed))
        fail("fractal.bailout", "is " + formatNumber(fractal.bailout) + " but must be at least the containment radius r_K = " +
                                    formatNumber(needed) + " of this constant and variant (points inside r_K may still be in the set)");

    const Slice slice = params.slice.effective();
    for (int axis = 0; axis < 3; ++axis)
        for (int index = 0; index < 8; ++index)
            if (!(std::abs(params.slice.base.axes[axis][index]) <= 1e9) || !(std::abs(params.slice.base.origin[index]) <= 1e9))
                fail("slice", "origin and axes must be finite numbers from -1e9 to 1e9");
    for (const PlaneRotation& rotation : params.slice.rotations) {
        if (rotation.first == rotation.second || rotation.first < 0 || rotation.first > 7 || rotation.second < 0 || rotation.second > 7)
            fail("slice.rotations", "a rotation plane must name two different axes");
        if (!(std::abs(rotation.degrees) <= 36000.0)) fail("slice.rotations", "degrees must be finite numbers from -36000 to 36000");
    }
    const Stretch stretch = stretchOf(slice);
    if (stretch.min < 1e-9 * std::max(1.0, stretch.max))
        fail("slice.axes", "the three axes are zero or parallel, so the slice is not 3-D; give three independent axes");
    // Linearly dependent axes (z = x + y) span a plane: the Gram determinant vanishes against
    // the product of the squared lengths (Hadamard's bound; 1 for orthogonal axes).
    {
        double gram[3][3] = {};
        for (int row = 0; row < 3; ++row)
            for (int column = 0; column < 3; ++column)
                for (int index = 0; index < 8; ++index) gram[row][column] += slice.axes[row][index] * slice.axes[column][index];
        const double determinant = gram[0][0] * (gram[1][1] * gram[2][2] - gram[1][2] * gram[2][1]) -
                                   gram[0][1] * (gram[1][0] * gram[2][2] - gram[1][2] * gram[2][0]) +
                                   gram[0][2] * (gram[1][0] * gram[2][1] - gram[1][1] * gram[2][0]);
        if (!(determinant > 1e-10 * gram[0][0] * gram[1][1] * gram[2][2]))
            fail("slice.axes", "the three axes are linearly dependent (one is a combination of the others), so the slice "
                               "is a plane, not 3-D; give three independent axes");
    }

    if (params.bounds && !(params.bounds->radius > 0.0)) fail("bounds.radius", "must be greater than 0");

    auto finite3 = [](const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    // Camera vectors within the parameter file's range (+-1e9), so lengths and directions
    // computed from them stay finite and exact enough to aim a ray.
    auto sane3 = [&](const glm::dvec3& v) { return finite3(v) && std::abs(v.x) <= 1e9 && std::abs(v.y) <= 1e9 && std::abs(v.z) <= 1e9; };
    if (params.bounds && (!sane3(params.bounds->center) || !(params.bounds->radius <= 1e6)))
        fail("bounds", "center must be 3 finite numbers from -1e9 to 1e9 and radius at most 1e6");
    const Camera& camera = params.camera;
    if (camera.position && !sane3(*camera.position)) fail("camera.position", "must be 3 finite numbers from -1e9 to 1e9");
    if (camera.target && !sane3(*camera.target)) fail("camera.target", "must be 3 finite numbers from -1e9 to 1e9");
    if (!sane3(camera.direction)) fail("camera.direction", "must be 3 finite numbers from -1e9 to 1e9");
    if (!sane3(camera.up)) fail("camera.up", "must be 3 finite numbers from -1e9 to 1e9");
    for (std::size_t index = 0; index < params.lights.size(); ++index)
        if (!finite3(params.lights[index].direction) || !finite3(params.lights[index].color) ||
            !std::isfinite(params.lights[index].intensity))
            fail("lights[" + std::to_string(index) + "]", "direction, color and intensity must be finite numbers");
    if (!(camera.fovDegrees > 0.0 && camera.fovDegrees < 170.0)) fail("camera.fov", "must be between 0 and 170 degrees");
    if (glm::length(camera.up) == 0.0) fail("camera.up", "must not be the zero vector");
    glm::dvec3 forward;
    if (camera.position) {
        const glm::dvec3 target = camera.target.value_or(glm::dvec3(0.0));
        forward = target - *camera.position;
        if (camera.target && glm::length(forward) == 0.0)
            fail("camera.position", "equals camera.target; the camera must look somewhere");
    } else {
        if (glm::length(camera.direction) == 0.0) fail("camera.direction", "must not be the zero vector");
        forward = -camera.direction;
    }
    if (glm::length(forward) > 0.0 && parallel(forward, camera.up))
        fail("camera.up", "is parallel to the viewing direction; choose an up vector across it");

    for (std::size_t index = 0; index < params.lights.size(); ++index)
        if (glm::length(params.lights[index].direction) == 0.0)
            fail("lights[" + std::to_string(index) + "].direction", "must not be the zero vector");
    if (params.material.palette.empty()) fail("material.palette", "must hold at least one colour");

    const RenderSettings& render = params.render;
    if (render.width < 1 || render.height < 1 || render.width > 16384 || render.height > 16384)
        fail("render.width", "width and height must be from 1 to 16384");
    if (render.samples < 1 || render.samples > 16) fail("render.samples", "must be from 1 to 16");
    if (!(render.stepFactor > 0.0 && render.stepFactor <= 1.0)) fail("render.step_factor", "must be greater than 0 and at most 1");
    if (!(render.maxStep > 0.0 && render.maxStep <= 1e6)) fail("render.max_step", "must be greater than 0 and at most 1e6");
    if (render.maxSteps < 1 || render.maxSteps > 1000000) fail("render.max_steps", "must be from 1 to 1000000");
    if (!(render.detail > 0.0 && render.detail <= 1000.0)) fail("render.detail", "must be greater than 0 and at most 1000");
    if (render.normals == NormalMethod::Analytic && fractal.variant != Variant::Dual)
        fail("render.normals", "\"analytic\" normals come from the dual part of the true algebra and need variant \"dual\"; "
                               "use \"central\" or \"auto\" with variant \"" + std::string(variantName(fractal.variant)) + "\"");
    if (params.output.path.empty()) fail("output.path", "must not be empty");
    if (!params.output.format) {
        std::string extension = params.output.path.substr(std::min(params.output.path.size(), params.output.path.rfind('.')));
        std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char ch) { return std::tolower(ch); });
        if (extension != ".png" && extension != ".exr")
            fail("output.path", "\"" + params.output.path + "\" must end in .png or .exr (or set output.format to png8, png16 or exr)");
    }

    const BakeSettings& bake = params.bake;
    if (bake.resolution < 8 || bake.resolution > 16384) fail("bake.resolution", "must be a whole number from 8 to 16384");
    if (bake.bounds) {
        for (int axis = 0; axis < 3; ++axis)
            if (!(bake.bounds->min[axis] < bake.bounds->max[axis]) || !(std::abs(bake.bounds->min[axis]) <= 1e6) ||
                !(std::abs(bake.bounds->max[axis]) <= 1e6))
                fail("bake.bounds", "min must be below max on every axis (x, y, z), with finite numbers from -1e6 to 1e6");
    }
    if (!(bake.bandWidth >= 1.0 && bake.bandWidth <= 32.0)) fail("bake.band_width", "must be from 1 to 32 voxels");
    if (bake.grids.empty()) fail("bake.grids", "must name at least one grid");
    if (!(bake.adaptivity >= 0.0 && bake.adaptivity <= 1.0)) fail("bake.adaptivity", "must be from 0 to 1");

    // Keyframes: a rotation track needs its rotation, and the parameters at every key must pass
    // the rules above (the frames between keys are checked when they are baked).
    for (const Track& track : params.animation) {
        if (track.target == AnimatedValue::RotationDegrees && track.rotation >= int(params.slice.rotations.size()))
            fail("animation." + trackKey(track), "animates rotation " + std::to_string(track.rotation) + " but slice.rotations has " +
                                                     std::to_string(params.slice.rotations.size()) + " (they count from 0)");
        for (const Keyframe& key : track.keys) {
            Params still = atFrame(params, key.frame);
            still.animation.clear();
            try {
                validate(still);
            } catch (const ParamError& error) {
                throw ParamError(error.key(), "animation: at frame " + formatNumber(key.frame) + " (a key of " +
                                                  trackKey(track) + "): " + error.what());
            }
        }
    }
}

std::string toJson(const Params& params) {
    OrderedJson document;
    document["version"] = kFormatVersion;
    if (!params.description.empty()) document["description"] = params.description;
    document["fractal"] = {{"c", vec8Json(toVec8(params.fractal.c))},
                           {"variant", variantName(params.fractal.variant)},
                           {"iterations", params.fractal.iterations},
                           {"bailout", params.fractal.bailout}};
    OrderedJson slice;
    const std::string names = axisNamesOf(params.slice.base);
    if (!names.empty()) {
        slice["axes"] = names;
    } else {
        slice["axes"] = OrderedJson::array();
        for (const Vec8& axis : params.slice.base.axes) slice["axes"].push_back(vec8Json(axis));
    }
    slice["origin"] = vec8Json(params.slice.base.origin);
    slice["rotations"] = OrderedJson::array();
    for (const PlaneRotation& rotation : params.slice.rotations)
        slice["rotations"].push_back({{"plane", axisName(rotation.first) + "," + axisName(rotation.second)},
                                      {"degrees", rotation.degrees}});
    document["slice"] = slice;
    if (params.bounds) {
        document["bounds"] = {{"center", vec3Json(params.bounds->center)}, {"radius", params.bounds->radius}};
    } else {
        document["bounds"] = "auto";
    }
    OrderedJson camera;
    if (params.camera.position) camera["position"] = vec3Json(*params.camera.position);
    if (params.camera.target) camera["target"] = vec3Json(*params.camera.target);
    camera["direction"] = vec3Json(params.camera.direction);
    camera["up"] = vec3Json(params.camera.up);
    camera["fov"] = params.camera.fovDegrees;
    document["camera"] = camera;
    document["lights"] = OrderedJson::array();
    for (const Light& light : params.lights)
        document["lights"].push_back(
            {{"direction", vec3Json(light.direction)}, {"color", vec3Json(light.color)}, {"intensity", light.intensity}});
    const Material& material = params.material;
    OrderedJson palette = OrderedJson::array();
    for (const glm::dvec3& color : material.palette) palette.push_back(vec3Json(color));
    document["material"] = {{"color", vec3Json(material.color)},
                            {"coloring", coloringName(material.coloring)},
                            {"palette", palette},
                            {"ambient", material.ambient},
                            {"diffuse", material.diffuse},
                            {"specular", material.specular},
                            {"shininess", material.shininess},
                            {"occlusion", material.occlusion},
                            {"shadows", material.shadows},
                            {"shadow_softness", material.shadowSoftness}};
    const RenderSettings& render = params.render;
    document["render"] = {{"width", render.width},
                          {"height", render.height},
                          {"samples", render.samples},
                          {"step_factor", render.stepFactor},
                          {"max_step", render.maxStep},
                          {"max_steps", render.maxSteps},
                          {"detail", render.detail},
                          {"normals", normalMethodName(render.normals)},
                          {"background", {{"top", vec3Json(render.backgroundTop)}, {"bottom", vec3Json(render.backgroundBottom)}}}};
    OrderedJson output{{"path", params.output.path}};
    if (params.output.format) output["format"] = imageFormatName(*params.output.format);
    document["output"] = output;
    const BakeSettings& bake = params.bake;
    OrderedJson grids = OrderedJson::array();
    for (const BakeGrid grid : bake.grids) grids.push_back(bakeGridName(grid));
    OrderedJson bakeJson{{"resolution", bake.resolution}};
    if (bake.bounds) {
        bakeJson["bounds"] = {{"min", vec3Json(bake.bounds->min)}, {"max", vec3Json(bake.bounds->max)}};
    } else {
        bakeJson["bounds"] = "auto";
    }
    bakeJson["band_width"] = bake.bandWidth;
    bakeJson["grids"] = grids;
    bakeJson["adaptivity"] = bake.adaptivity;
    bakeJson["mesh_colors"] = bake.meshColors;
    document["bake"] = bakeJson;
    OrderedJson animation = OrderedJson::object();
    for (const Track& track : params.animation) {
        OrderedJson keys = OrderedJson::array();
        for (const Keyframe& key : track.keys) {
            OrderedJson value = track.target == AnimatedValue::Constant ? OrderedJson(key.value) : OrderedJson(key.value.at(0));
            keys.push_back({{"frame", key.frame}, {"value", value}, {"interpolation", nameOf(key.interpolation, kInterpolations)}});
        }
        animation[trackKey(track)] = keys;
    }
    document["animation"] = animation;
    return compactNumberArrays(document.dump(2)) + "\n";
}

void saveParams(const Params& params, const std::string& path, Existing existing) {
    const std::string text = toJson(params);
    AtomicFile target(path, existing);
    target.stream() << text;
    target.commit();
}

std::string_view coloringName(Coloring coloring) { return nameOf(coloring, kColorings); }
std::string_view normalMethodName(NormalMethod method) { return nameOf(method, kNormalMethods); }
std::string_view imageFormatName(ImageFormat format) { return nameOf(format, kFormats); }

ImageFormat formatFor(const OutputSettings& output) {
    if (output.format) return *output.format;
    std::string extension;
    const std::size_t dot = output.path.rfind('.');
    if (dot != std::string::npos) extension = output.path.substr(dot + 1);
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char ch) { return std::tolower(ch); });
    return extension == "exr" ? ImageFormat::Exr : ImageFormat::Png8;
}

namespace {

/// The slope at key `index` of one component for smooth interpolation: 0 at the first and last
/// key and where the values turn (a local extremum), else the weighted harmonic mean of the two
/// neighbouring secant slopes (Fritsch-Butland), which keeps the cubic monotone between keys.
double smoothSlope(const std::vector<Keyframe>& keys, std::size_t index, std::size_t component) {
    if (index == 0 || index + 1 >= keys.size()) return 0.0;
    const double h0 = keys[index].frame - keys[index - 1].frame;
    const double h1 = keys[index + 1].frame - keys[index].frame;
    const double d0 = (keys[index].value[component] - keys[index - 1].value[component]) / h0;
    const double d1 = (keys[index + 1].value[component] - keys[index].value[component]) / h1;
    if (d0 * d1 <= 0.0) return 0.0;
    const double w0 = 2.0 * h1 + h0, w1 = h1 + 2.0 * h0;
    return (w0 + w1) / (w0 / d0 + w1 / d1);
}

/// The track's value at `frame`, one number per component.
std::vector<double> trackValue(const Track& track, double frame) {
    const std::vector<Keyframe>& keys = track.keys;
    if (frame <= keys.front().frame) return keys.front().value;
    if (frame >= keys.back().frame) return keys.back().value;
    std::size_t index = 0;
    while (!(frame < keys[index + 1].frame)) ++index;
    const Keyframe& from = keys[index];
    const Keyframe& to = keys[index + 1];
    const double span = to.frame - from.frame;
    const double t = (frame - from.frame) / span;
    std::vector<double> value(from.value.size());
    for (std::size_t component = 0; component < value.size(); ++component) {
        const double v0 = from.value[component], v1 = to.value[component];
        if (from.interpolation == Interpolation::Linear) {
            value[component] = v0 + t * (v1 - v0);
            continue;
        }
        // Cubic Hermite between the keys with the slopes above.
        const double m0 = smoothSlope(keys, index, component) * span;
        const double m1 = smoothSlope(keys, index + 1, component) * span;
        const double t2 = t * t, t3 = t2 * t;
        value[component] = (2 * t3 - 3 * t2 + 1) * v0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * v1 + (t3 - t2) * m1;
    }
    return value;
}

}  // namespace

Params atFrame(const Params& params, double frame) {
    Params result = params;
    for (const Track& track : params.animation) {
        const std::vector<double> value = trackValue(track, frame);
        switch (track.target) {
            case AnimatedValue::Constant: {
                Vec8 c;
                std::copy(value.begin(), value.end(), c.begin());
                result.fractal.c = toDualQuat(c);
                break;
            }
            case AnimatedValue::Iterations: result.fractal.iterations = std::max(1, int(std::lround(value[0]))); break;
            case AnimatedValue::Bailout: result.fractal.bailout = value[0]; break;
            case AnimatedValue::RotationDegrees:
                if (track.rotation < int(result.slice.rotations.size())) result.slice.rotations[track.rotation].degrees = value[0];
                break;
        }
    }
    return result;
}

std::string trackKey(const Track& track) {
    switch (track.target) {
        case AnimatedValue::Constant: return "fractal.c";
        case AnimatedValue::Iterations: return "fractal.iterations";
        case AnimatedValue::Bailout: return "fractal.bailout";
        case AnimatedValue::RotationDegrees: return "slice.rotations[" + std::to_string(track.rotation) + "].degrees";
    }
    return "unknown";
}

std::string_view bakeGridName(BakeGrid grid) { return nameOf(grid, kBakeGrids); }

bool hasGrid(const BakeSettings& bake, BakeGrid grid) {
    return std::find(bake.grids.begin(), bake.grids.end(), grid) != bake.grids.end();
}

}  // namespace dqj

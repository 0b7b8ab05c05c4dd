// The parameter file's reader: JSON in, Params out. Each value is checked against its schema
// field (types and ranges, param_check.hpp); the shapes with more than one form (axes, bounds,
// rotation planes, the animation) are read here. Every message names the file, the dotted key,
// what was wrong and what is allowed.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "files/atomic_file.hpp"
#include "dqjulia/param_file.hpp"
#include "dqjulia/schema.hpp"
#include "platform/platform.hpp"
#include "params/json_text.hpp"
#include "params/param_check.hpp"

namespace dqj {

ParamError::ParamError(std::string key, const std::string& message)
    : std::runtime_error(printableText(message)), key_(std::move(key)) {}

namespace {

using json::describe;
using json::formatNumber;
using json::Json;

constexpr int kFormatVersion = 1;

/// Walks one JSON object: reads known keys, each checked against its schema field, then
/// rejects any key it was not asked about, suggesting the nearest known one.
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

    /// `value` at the full key `key`, checked against the schema's field `fieldKey`.
    const Json& checked(const Json& value, const std::string& key, const std::string& fieldKey) const {
        detail::checkValue(schema::field(fieldKey), value, key, source_ + ": ");
        return value;
    }
    const Json& checked(const Json& value, const std::string& key) const { return checked(value, key, key); }

    /// Reads `key` into `out` if present, checked against its schema field.
    template <typename T>
    void read(const std::string& key, T& out) {
        if (const Json* value = find(key)) out = checked(*value, keyPath(key)).template get<T>();
    }
    void read(const std::string& key, glm::dvec3& out) {
        if (const Json* value = find(key)) out = vec3(*value, keyPath(key));
    }
    glm::dvec3 vec3(const Json& value, const std::string& key) const { return vec3(value, key, key); }
    glm::dvec3 vec3(const Json& value, const std::string& key, const std::string& fieldKey) const {
        checked(value, key, fieldKey);
        return {value[0].get<double>(), value[1].get<double>(), value[2].get<double>()};
    }
    /// 8 numbers, each within the range of the field `fieldKey` (a Vec8, a DualQuat, or one axis of slice.axes).
    Vec8 vec8(const Json& value, const std::string& key, const std::string& fieldKey) const {
        detail::checkVector(schema::field(fieldKey), value, key, source_ + ": ", 8);
        Vec8 v;
        for (std::size_t index = 0; index < 8; ++index) v[index] = value[index].get<double>();
        return v;
    }
    /// A choice by name, checked against the choices of the field `fieldKey` (a Choice, an item of
    /// a ChoiceSet, or the animation's interpolations).
    template <typename Enum>
    Enum choice(const Json& value, const std::string& key, const std::string& fieldKey) const {
        const schema::Field& field = schema::field(fieldKey);
        detail::checkChoice(field, value, key, source_ + ": ");
        return static_cast<Enum>(*schema::choiceIndex(field, value.get_ref<const std::string&>()));  // checked
    }
    template <typename Enum>
    Enum choice(const Json& value, const std::string& key) const {
        return choice<Enum>(value, key, key);
    }
    template <typename Enum>
    void readChoice(const std::string& key, Enum& out) {
        if (const Json* value = find(key)) out = choice<Enum>(*value, keyPath(key));
    }

    /// Rejects keys nobody asked for ("unknown key 'iteratons'; did you mean 'iterations'?").
    void finish() const {
        for (const auto& item : node_.items()) {
            if (std::find(known_.begin(), known_.end(), item.key()) != known_.end()) continue;
            std::string nearest;
            std::size_t best = std::string::npos;
            for (const std::string& candidate : known_) {
                if (item.key().size() > 2 * candidate.size() + 8) continue;  // nothing near (and a long key costs)
                const std::size_t distance = json::editDistance(item.key(), candidate);
                if (distance < best) {
                    best = distance;
                    nearest = candidate;
                }
            }
            const std::string key = inputExcerpt(item.key());
            std::string message = "unknown key \"" + key + "\"";
            if (best <= std::max<std::size_t>(2, item.key().size() / 3))
                message += "; did you mean \"" + nearest + "\"?";
            std::string allowed;
            for (const std::string& candidate : known_) allowed += (allowed.empty() ? "" : ", ") + candidate;
            fail(keyPath(key), message + " (allowed here: " + allowed + ")");
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

std::string indexed(const std::string& key, std::size_t index) { return key + "[" + std::to_string(index) + "]"; }

void readFractal(ObjectReader reader, Fractal& fractal) {
    if (const Json* value = reader.find("c")) fractal.c = toDualQuat(reader.vec8(*value, "fractal.c", "fractal.c"));
    reader.readChoice("variant", fractal.variant);
    reader.read("iterations", fractal.iterations);
    reader.read("bailout", fractal.bailout);
    reader.finish();
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
                slice.base.axes[axis] = reader.vec8((*value)[axis], indexed(key, axis), key);
        } else {
            reader.fail(key, "must be axis names like \"a.s,a.i,a.j\" or an array of three 8-number vectors, got " +
                                 describe(*value));
        }
    }
    if (const Json* value = reader.find("origin"))
        slice.base.origin = reader.vec8(*value, "slice.origin", "slice.origin");
    if (const Json* value = reader.find("rotations")) {
        const std::string key = reader.keyPath("rotations");
        if (!value->is_array())
            reader.fail(key, "must be an array of {\"plane\": \"a.j,b.s\", \"degrees\": 30}, got " + describe(*value));
        slice.rotations.clear();
        for (std::size_t index = 0; index < value->size(); ++index) {
            ObjectReader item((*value)[index], indexed(key, index), reader.source());
            PlaneRotation rotation;
            std::string plane;
            item.read("plane", plane);
            const std::size_t comma = plane.find(',');
            const auto first = parseAxisName(plane.substr(0, comma));
            const auto second = comma == std::string::npos ? std::nullopt : parseAxisName(plane.substr(comma + 1));
            if (!first || !second || *first == *second)
                item.fail(item.keyPath("plane"),
                          "must name two different axes like \"a.j,b.s\" (axes: a.s a.i a.j a.k b.s "
                          "b.i b.j b.k), got \"" +
                              inputExcerpt(plane) + "\"");
            rotation.first = *first;
            rotation.second = *second;
            item.read("degrees", rotation.degrees);
            item.finish();
            slice.rotations.push_back(rotation);
        }
    }
    reader.finish();
}

void readBounds(ObjectReader reader, std::optional<Bounds>& bounds) {
    Bounds result;
    reader.read("center", result.center);
    reader.read("radius", result.radius);
    reader.finish();
    bounds = result;
}

void readCamera(ObjectReader reader, Camera& camera) {
    if (const Json* value = reader.find("position")) camera.position = reader.vec3(*value, reader.keyPath("position"));
    if (const Json* value = reader.find("target")) camera.target = reader.vec3(*value, reader.keyPath("target"));
    reader.read("direction", camera.direction);
    reader.read("up", camera.up);
    reader.read("fov", camera.fovDegrees);
    reader.finish();
}

void readLights(ObjectReader& parent, const Json& value, std::vector<Light>& lights) {
    const std::string key = parent.keyPath("lights");
    if (!value.is_array())
        parent.fail(key,
                    "must be an array of lights {\"direction\", \"color\", \"intensity\"}, got " + describe(value));
    lights.clear();
    for (std::size_t index = 0; index < value.size(); ++index) {
        ObjectReader reader(value[index], indexed(key, index), parent.source());
        Light light;
        reader.read("direction", light.direction);
        reader.read("color", light.color);
        reader.read("intensity", light.intensity);
        reader.finish();
        lights.push_back(light);
    }
}

void readMaterial(ObjectReader reader, Material& material) {
    reader.read("color", material.color);
    reader.readChoice("coloring", material.coloring);
    if (const Json* value = reader.find("palette")) {
        const std::string key = reader.keyPath("palette");
        reader.checked(*value, key);
        material.palette.clear();
        for (std::size_t index = 0; index < value->size(); ++index)
            material.palette.push_back(reader.vec3((*value)[index], indexed(key, index)));
    }
    reader.read("ambient", material.ambient);
    reader.read("diffuse", material.diffuse);
    reader.read("specular", material.specular);
    reader.read("shininess", material.shininess);
    reader.read("occlusion", material.occlusion);
    reader.read("shadows", material.shadows);
    reader.read("shadow_softness", material.shadowSoftness);
    reader.finish();
}

void readRender(ObjectReader reader, RenderSettings& render) {
    reader.read("width", render.width);
    reader.read("height", render.height);
    reader.read("samples", render.samples);
    reader.read("step_factor", render.stepFactor);
    reader.read("max_step", render.maxStep);
    reader.read("max_steps", render.maxSteps);
    reader.read("detail", render.detail);
    reader.readChoice("normals", render.normals);
    if (const Json* value = reader.find("background")) {
        const std::string key = reader.keyPath("background");
        if (value->is_array()) {  // one colour for the whole background
            render.backgroundTop = render.backgroundBottom = reader.vec3(*value, key, key + ".top");
        } else {
            ObjectReader background(*value, key, reader.source());
            background.read("top", render.backgroundTop);
            background.read("bottom", render.backgroundBottom);
            background.finish();
        }
    }
    reader.finish();
}

void readBake(ObjectReader reader, BakeSettings& bake) {
    reader.read("resolution", bake.resolution);
    if (const Json* value = reader.find("bounds")) {
        if (value->is_string() && value->get<std::string>() == "auto") {
            bake.bounds.reset();
        } else {
            ObjectReader box(*value, reader.keyPath("bounds"), reader.source());
            Box result;
            const Json* min = box.find("min");
            const Json* max = box.find("max");
            if (!min || !max) box.fail(box.path(), "must be \"auto\" or {\"min\": [x, y, z], \"max\": [x, y, z]}");
            result.min = box.vec3(*min, box.keyPath("min"));
            result.max = box.vec3(*max, box.keyPath("max"));
            box.finish();
            bake.bounds = result;
        }
    }
    reader.read("band_width", bake.bandWidth);
    if (const Json* value = reader.find("grids")) {
        const std::string key = reader.keyPath("grids");
        reader.checked(*value, key);
        bake.grids.clear();
        for (std::size_t index = 0; index < value->size(); ++index)
            bake.grids.push_back(reader.choice<BakeGrid>((*value)[index], indexed(key, index), key));
    }
    reader.read("adaptivity", bake.adaptivity);
    reader.read("max_faces", bake.maxFaces);
    reader.read("mesh_colors", bake.meshColors);
    reader.read("color_depth", bake.colorDepth);
    reader.finish();
}

/// "slice.rotations[3].degrees" -> 3; std::nullopt for anything else.
std::optional<int> rotationTrackIndex(const std::string& key) {
    const std::string prefix = "slice.rotations[", suffix = "].degrees";
    if (key.size() <= prefix.size() + suffix.size() || key.rfind(prefix, 0) != 0 ||
        key.compare(key.size() - suffix.size(), suffix.size(), suffix) != 0)
        return std::nullopt;
    const std::string digits = key.substr(prefix.size(), key.size() - prefix.size() - suffix.size());
    if (digits.empty() || digits.size() > 4 ||
        !std::all_of(digits.begin(), digits.end(), [](unsigned char ch) { return std::isdigit(ch); }))
        return std::nullopt;
    return std::stoi(digits);
}

/// The "animation" object: {"fractal.c": [{"frame": 1, "value": [...], "interpolation": "smooth"}, ...], ...}.
/// Each key's values are checked against the field it animates.
void readAnimation(const Json& node, const std::string& source, std::vector<Track>& tracks) {
    ObjectReader reader(node, "animation", source);  // checks that it is an object
    tracks.clear();
    std::string animatable;
    for (const schema::Field& field : schema::fields())
        if (field.has(schema::kAnimatable))
            animatable += (animatable.empty() ? "" : ", ") + (field.key == "slice.rotations[].degrees"
                                                                  ? std::string("slice.rotations[i].degrees")
                                                                  : std::string(field.key));
    for (const auto& item : node.items()) {
        const std::string key = reader.keyPath(item.key());
        Track track;
        if (item.key() == "fractal.c") {
            track.target = AnimatedValue::Constant;
        } else if (item.key() == "fractal.iterations") {
            track.target = AnimatedValue::Iterations;
        } else if (item.key() == "fractal.bailout") {
            track.target = AnimatedValue::Bailout;
        } else if (const auto rotation = rotationTrackIndex(item.key())) {
            track.target = AnimatedValue::RotationDegrees;
            track.rotation = *rotation;
        } else {
            reader.fail(key, "cannot be animated (animatable: " + animatable + ")");
        }
        const std::string animated = trackKey(track);
        const Json& keys = item.value();
        if (!keys.is_array() || keys.empty())
            reader.fail(key,
                        "must be a non-empty array of keys {\"frame\": 1, \"value\": ..., \"interpolation\": "
                        "\"linear\"}, got " +
                            describe(keys));
        for (std::size_t index = 0; index < keys.size(); ++index) {
            ObjectReader keyReader(keys[index], indexed(key, index), source);
            Keyframe keyframe;
            const Json* frame = keyReader.find("frame");
            const Json* value = keyReader.find("value");
            if (!frame || !value) keyReader.fail(keyReader.path(), "needs \"frame\" and \"value\"");
            if (!frame->is_number() || !std::isfinite(frame->get<double>()) || std::abs(frame->get<double>()) > 1e6)
                keyReader.fail(keyReader.keyPath("frame"),
                               "must be a number from -1e6 to 1e6, got " + describe(*frame));
            keyframe.frame = frame->get<double>();
            keyReader.checked(*value, keyReader.keyPath("value"), animated);
            if (track.target == AnimatedValue::Constant)
                keyframe.value = value->get<std::vector<double>>();
            else
                keyframe.value = {value->get<double>()};
            if (const Json* interpolation = keyReader.find("interpolation"))
                keyframe.interpolation =
                    keyReader.choice<Interpolation>(*interpolation, keyReader.keyPath("interpolation"), "animation");
            keyReader.finish();
            if (!track.keys.empty() && !(keyframe.frame > track.keys.back().frame))
                keyReader.fail(keyReader.keyPath("frame"),
                               "frames must increase from key to key: " + formatNumber(keyframe.frame) + " follows " +
                                   formatNumber(track.keys.back().frame));
            track.keys.push_back(keyframe);
        }
        tracks.push_back(track);
    }
}

void readOutput(ObjectReader reader, OutputSettings& output) {
    reader.read("path", output.path);
    if (const Json* value = reader.find("format")) output.format = reader.choice<ImageFormat>(*value, "output.format");
    reader.finish();
}

Params readDocument(const Json& document, const std::string& source, Validation validation);

}  // namespace

Params parseParams(const std::string& jsonText, const std::string& source, Validation validation) {
    if (jsonText.size() > kMaxParamsBytes)
        throw ParamError("", source + ": the document has more than " + std::to_string(kMaxParamsBytes >> 20) +
                                 " MiB; a parameter file is a few kilobytes");
    const Json document = json::parseDocument(jsonText, source);
    try {
        return readDocument(document, source, validation);
    } catch (const Json::exception& error) {  // a shape no check above foresaw: still the document's fault
        throw ParamError("", source + ": malformed value: " + std::string(error.what()));
    }
}

namespace {

Params readDocument(const Json& document, const std::string& source, Validation validation) {
    Params params;
    ObjectReader root(document, "", source);
    if (const Json* value = root.find("version")) {
        if (!value->is_number_integer() || value->get<int>() != kFormatVersion)
            root.fail("version", "this dqjulia reads parameter format version " + std::to_string(kFormatVersion) +
                                     ", got " + describe(*value));
    }
    root.read("description", params.description);
    if (const Json* value = root.find("fractal")) readFractal(ObjectReader(*value, "fractal", source), params.fractal);
    if (const Json* value = root.find("slice")) readSlice(ObjectReader(*value, "slice", source), params.slice);
    if (const Json* value = root.find("bounds")) {
        if (!(value->is_string() && value->get<std::string>() == "auto"))
            readBounds(ObjectReader(*value, "bounds", source), params.bounds);
    }
    if (const Json* value = root.find("camera")) readCamera(ObjectReader(*value, "camera", source), params.camera);
    if (const Json* value = root.find("lights")) readLights(root, *value, params.lights);
    if (const Json* value = root.find("material"))
        readMaterial(ObjectReader(*value, "material", source), params.material);
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

}  // namespace

Params loadParams(const std::string& path, Validation validation) {
    const std::string source = "parameter file '" + inputExcerpt(path) + "'";
    auto fail = [&](const std::string& reason) { return ParamError("", "cannot read " + source + ": " + reason); };
    const int fd = platform::openForReading(path);
    if (fd < 0) throw fail(std::strerror(errno));
    // Read at most one byte beyond the limit, so a never-ending file (/dev/zero, a stalled
    // pipe's writer) cannot grow the buffer without bound. A signal (Ctrl-C) ends the read.
    std::string text;
    char chunk[65536];
    int error = 0;
    while (text.size() <= kMaxParamsBytes) {
        const std::int64_t got = platform::readSome(fd, chunk, sizeof chunk);
        if (got < 0) error = errno;
        if (got <= 0) break;
        text.append(chunk, std::size_t(got));
    }
    platform::closeFile(fd);
    if (error == EINTR) throw fail("interrupted");
    if (error == EISDIR) throw fail(std::strerror(error));  // a folder given as the file: bad input
    // The disk or the network failing is not bad input (exit 1, DQJ_ERROR_IO): a retry may help.
    if (error) throw std::system_error(error, std::generic_category(), printableText("cannot read " + source));
    if (text.size() > kMaxParamsBytes)
        throw fail("larger than " + std::to_string(kMaxParamsBytes >> 20) +
                   " MiB; a parameter file is a few kilobytes");
    return parseParams(text, inputExcerpt(path), validation);
}

}  // namespace dqj

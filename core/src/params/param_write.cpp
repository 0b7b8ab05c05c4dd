// The parameter file's writer: the complete document for a Params (every key written, numbers
// exact), which the reader reads back as the same Params.
#include "files/atomic_file.hpp"
#include "dqjulia/param_file.hpp"
#include "dqjulia/schema.hpp"
#include "params/json_text.hpp"

namespace dqj {

namespace {

constexpr int kFormatVersion = 1;

json::OrderedJson vec3Json(const glm::dvec3& v) { return json::OrderedJson::array({v.x, v.y, v.z}); }
json::OrderedJson vec8Json(const Vec8& v) { return json::OrderedJson(std::vector<double>(v.begin(), v.end())); }

}  // namespace

std::string toJson(const Params& params) {
    json::OrderedJson document;
    document["version"] = kFormatVersion;
    if (!params.description.empty()) document["description"] = params.description;
    document["fractal"] = {{"c", vec8Json(toVec8(params.fractal.c))},
                           {"variant", variantName(params.fractal.variant)},
                           {"iterations", params.fractal.iterations},
                           {"bailout", params.fractal.bailout}};
    json::OrderedJson slice;
    const std::string names = axisNamesOf(params.slice.base);
    if (!names.empty()) {
        slice["axes"] = names;
    } else {
        slice["axes"] = json::OrderedJson::array();
        for (const Vec8& axis : params.slice.base.axes) slice["axes"].push_back(vec8Json(axis));
    }
    slice["origin"] = vec8Json(params.slice.base.origin);
    slice["rotations"] = json::OrderedJson::array();
    for (const PlaneRotation& rotation : params.slice.rotations)
        slice["rotations"].push_back(
            {{"plane", axisName(rotation.first) + "," + axisName(rotation.second)}, {"degrees", rotation.degrees}});
    document["slice"] = slice;
    if (params.bounds) {
        document["bounds"] = {{"center", vec3Json(params.bounds->center)}, {"radius", params.bounds->radius}};
    } else {
        document["bounds"] = "auto";
    }
    json::OrderedJson camera;
    if (params.camera.position) camera["position"] = vec3Json(*params.camera.position);
    if (params.camera.target) camera["target"] = vec3Json(*params.camera.target);
    camera["direction"] = vec3Json(params.camera.direction);
    camera["up"] = vec3Json(params.camera.up);
    camera["fov"] = params.camera.fovDegrees;
    document["camera"] = camera;
    document["lights"] = json::OrderedJson::array();
    for (const Light& light : params.lights)
        document["lights"].push_back({{"direction", vec3Json(light.direction)},
                                      {"color", vec3Json(light.color)},
                                      {"intensity", light.intensity}});
    const Material& material = params.material;
    json::OrderedJson palette = json::OrderedJson::array();
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
                          {"background",
                           {{"top", vec3Json(render.backgroundTop)}, {"bottom", vec3Json(render.backgroundBottom)}}}};
    json::OrderedJson output{{"path", params.output.path}};
    if (params.output.format) output["format"] = imageFormatName(*params.output.format);
    document["output"] = output;
    const BakeSettings& bake = params.bake;
    json::OrderedJson grids = json::OrderedJson::array();
    for (const BakeGrid grid : bake.grids) grids.push_back(bakeGridName(grid));
    json::OrderedJson bakeJson{{"resolution", bake.resolution}};
    if (bake.bounds) {
        bakeJson["bounds"] = {{"min", vec3Json(bake.bounds->min)}, {"max", vec3Json(bake.bounds->max)}};
    } else {
        bakeJson["bounds"] = "auto";
    }
    bakeJson["band_width"] = bake.bandWidth;
    bakeJson["grids"] = grids;
    bakeJson["adaptivity"] = bake.adaptivity;
    bakeJson["max_faces"] = bake.maxFaces;
    bakeJson["mesh_colors"] = bake.meshColors;
    bakeJson["color_depth"] = bake.colorDepth;
    document["bake"] = bakeJson;
    json::OrderedJson animation = json::OrderedJson::object();
    for (const Track& track : params.animation) {
        json::OrderedJson keys = json::OrderedJson::array();
        for (const Keyframe& key : track.keys) {
            json::OrderedJson value = track.target == AnimatedValue::Constant ? json::OrderedJson(key.value)
                                                                              : json::OrderedJson(key.value.at(0));
            keys.push_back({{"frame", key.frame},
                            {"value", value},
                            {"interpolation", schema::choiceName("animation", int(key.interpolation))}});
        }
        animation[trackKey(track)] = keys;
    }
    document["animation"] = animation;
    return json::compactNumberArrays(document.dump(2)) + "\n";
}

void saveParams(const Params& params, const std::string& path, Existing existing) {
    const std::string text = toJson(params);
    AtomicFile target(path, existing);
    target.stream() << text;
    target.commit();
}

}  // namespace dqj

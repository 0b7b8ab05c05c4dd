// The schema (schema.hpp) against the reader, the writer and validate(): every key the file
// holds is described, every described range is the one enforced, in the file and in Params.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "dqjulia/params.hpp"

namespace dqj {
namespace {

using Json = nlohmann::json;

/// Every key of a document, list items written "key[]" as the schema names them.
void collectKeys(const Json& node, const std::string& key, std::set<std::string>& keys, bool listItem = false) {
    if (!key.empty() && !listItem) keys.insert(key);
    if (key == "animation") return;
    if (node.is_object())
        for (const auto& item : node.items())
            collectKeys(item.value(), key.empty() ? item.key() : key + "." + item.key(), keys);
    const schema::Field* field = key.empty() ? nullptr : schema::find(key);
    if (node.is_array() && field && (field->type == schema::Type::List || field->type == schema::Type::ColorList))
        for (const Json& item : node) collectKeys(item, key + "[]", keys, field->type == schema::Type::List);
}

Json schemaDocument() { return Json::parse(schema::schemaJson()); }

TEST(Schema, DescribesEveryKeyTheWriterWrites) {
    std::set<std::string> written;
    collectKeys(Json::parse(toJson(Params{})), "", written);
    written.erase("version");
    for (const std::string& key : written)
        EXPECT_NE(schema::find(key), nullptr) << key << " is written but not in the schema";
    for (const schema::Field& field : schema::fields()) {
        EXPECT_FALSE(field.label.empty()) << field.key;
        EXPECT_FALSE(field.help.empty()) << field.key;
    }
}

TEST(Schema, EveryValueKeyHasADefaultFromTheStructs) {
    const Json document = schemaDocument();
    ASSERT_EQ(document["fields"].size(), schema::fields().size());
    for (const Json& entry : document["fields"]) {
        if (entry["type"] == "object" && !entry.contains("auto")) continue;
        EXPECT_TRUE(entry.contains("default")) << entry["key"];
    }
    auto fieldOf = [&](const std::string& key) {
        for (const Json& entry : document["fields"])
            if (entry["key"] == key) return entry;
        return Json();
    };
    const Params defaults;
    EXPECT_EQ(fieldOf("fractal.iterations")["default"], defaults.fractal.iterations);
    EXPECT_EQ(fieldOf("bake.resolution")["default"], defaults.bake.resolution);
    EXPECT_EQ(fieldOf("material.shininess")["default"], defaults.material.shininess);
    EXPECT_EQ(fieldOf("camera.position")["default"], nullptr);
    EXPECT_EQ(fieldOf("bounds")["default"], "auto");
    EXPECT_EQ(fieldOf("fractal.variant")["choices"].size(), 3u);
}

/// A default document with `key` (a number field) set to `value`; list fields at item 0.
Json withValue(const std::string& key, double value, bool integer) {
    Json document = Json::parse(toJson(Params{}));
    document["slice"]["rotations"] = Json::array({{{"plane", "a.j,b.s"}, {"degrees", 0.0}}});
    document["bounds"] = {{"center", {0.0, 0.0, 0.0}}, {"radius", 2.0}};
    Json* node = &document;
    std::size_t start = 0;
    while (true) {
        const std::size_t dot = key.find('.', start);
        std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
        const bool item = part.size() > 2 && part.substr(part.size() - 2) == "[]";
        if (item) part.resize(part.size() - 2);
        node = &(*node)[part];
        if (item) node = &(*node)[0];
        if (dot == std::string::npos) break;
        start = dot + 1;
    }
    *node = integer ? Json(static_cast<long long>(value)) : Json(value);
    return document;
}

TEST(Schema, TheReaderEnforcesEveryNumberRangeItDescribes) {
    int checked = 0;
    for (const schema::Field& field : schema::fields()) {
        const bool integer = field.type == schema::Type::Integer;
        if (!integer && field.type != schema::Type::Number) continue;
        const std::string key(field.key);
        auto accepts = [&](double value) {
            try {
                parseParams(withValue(key, value, integer).dump(), "test.json", Validation::TypesOnly);
                return true;
            } catch (const ParamError& error) {
                EXPECT_NE(std::string(error.what()).find(key.substr(0, key.find('['))), std::string::npos)
                    << error.what();
                return false;
            }
        };
        const double step = integer ? 1.0 : std::max(1e-9, std::abs(field.max - field.min) * 1e-6);
        EXPECT_EQ(accepts(field.min), !field.minExclusive) << key << " = min " << field.min;
        EXPECT_EQ(accepts(field.max), !field.maxExclusive) << key << " = max " << field.max;
        EXPECT_FALSE(accepts(field.min - step)) << key << " below min";
        if (field.max < 1e300) EXPECT_FALSE(accepts(field.max * (1 + 1e-9) + step)) << key << " above max";
        EXPECT_TRUE(accepts(0.5 * (field.min + field.max))) << key << " inside";
        ++checked;
    }
    EXPECT_GE(checked, 20);
}

TEST(Schema, ValidateChecksTheSameRangesOnParams) {
    Params params;
    params.render.samples = 17;
    EXPECT_THROW(validate(params), ParamError);
    params = Params{};
    params.material.occlusion = 1.5;
    try {
        validate(params);
        ADD_FAILURE() << "occlusion 1.5 passed";
    } catch (const ParamError& error) {
        EXPECT_EQ(error.key(), "material.occlusion");
        EXPECT_NE(std::string(error.what()).find("at most 1"), std::string::npos) << error.what();
    }
    params = Params{};
    params.lights[1].intensity = std::nan("");
    EXPECT_THROW(validate(params), ParamError);
}

TEST(Schema, ChoiceNamesFollowTheEnums) {
    EXPECT_EQ(coloringName(Coloring::Iterations), "iterations");
    EXPECT_EQ(normalMethodName(NormalMethod::CentralDifferences), "central");
    EXPECT_EQ(imageFormatName(ImageFormat::Exr), "exr");
    EXPECT_EQ(bakeGridName(BakeGrid::Trap), "trap");
    EXPECT_EQ(schema::choiceName("fractal.variant", int(Variant::PaperCoupled)), variantName(Variant::PaperCoupled));
    EXPECT_EQ(schema::choiceName("fractal.variant", int(Variant::Dual)), variantName(Variant::Dual));
}

}  // namespace
}  // namespace dqj

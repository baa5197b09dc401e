#include "peelcd/io/error.h"
#include "peelcd/io/mesh_io.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

using namespace peelcd;

namespace {
std::string error_of(const std::string& json) {
  try {
    parse_scene(json, "scene.json", "base");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("a scene with only objects takes every default", "[scene]") {
  const Scene s = parse_scene(R"({"objects":[{"mesh":"m/a.obj"},{"name":"b","mesh":"b.obj"}]})", "s.json", "dir");
  REQUIRE(s.objects.size() == 2);
  CHECK(s.objects[0].name == "object0");
  CHECK(s.objects[0].mesh_path == "dir/m/a.obj");
  CHECK(s.objects[1].name == "b");
  CHECK(s.objects[1].transform.scale == 1.0);
  const DetectOptions d;
  CHECK(s.options.resolution == d.resolution);
  CHECK(s.options.budget == 512);
  CHECK(s.options.ids == d.ids);
  CHECK(s.options.peel == d.peel);
  CHECK(s.options.views == d.views);
  CHECK(s.options.slope == d.slope);
  CHECK(s.options.epsilon == 0.0);
}

TEST_CASE("a scene may set the texels per median edge", "[scene]") {
  CHECK(parse_scene(R"({"objects":[{"mesh":"a.obj"}],"edge_texels":6.5})", "s.json", "dir").options.edge_texels == 6.5);
  CHECK(parse_scene(R"({"objects":[{"mesh":"a.obj"}],"edge_texels":0})", "s.json", "dir").options.edge_texels == 0.0);
  CHECK(parse_scene(R"({"objects":[{"mesh":"a.obj"}]})", "s.json", "dir").options.edge_texels == DetectOptions{}.edge_texels);
}

TEST_CASE("a scene may fuse 1, 2 or 3 views", "[scene]") {
  for (int views = 1; views <= 3; ++views) {
    const std::string json = R"({"objects":[{"mesh":"a.obj"}],"views":)" + std::to_string(views) + "}";
    CHECK(parse_scene(json, "s.json", "dir").options.views == views);
  }
}

TEST_CASE("the default scene file parses to docs/design.md's configuration", "[scene]") {
  const Scene s = load_scene(std::string(PEELCD_FIXTURES) + "/scenes/bunny_dragon.json");
  REQUIRE(s.objects.size() == 2);
  CHECK(s.objects[1].transform.scale == 2.5);
  CHECK(s.objects[1].transform.translate == Vec3(0.8, -0.5, 0));
  CHECK(s.objects[1].transform.degrees == 0.0);
}

TEST_CASE("transforms apply scale, then rotation, then translation", "[scene]") {
  const Scene s = parse_scene(
      R"({"objects":[{"mesh":"a.obj","transform":{"scale":2,"rotate":{"axis":[0,0,1],"degrees":90},"translate":[1,0,0]}}]})",
      "s.json", ".");
  const Vec3 p = s.objects[0].transform.apply(Vec3(1, 0, 0));
  CHECK((p - Vec3(1, 2, 0)).norm() < 1e-12);
}

TEST_CASE("bad scenes name the file, the key and the problem", "[scene]") {
  CHECK_THAT(error_of("{"), Catch::Contains("scene.json") && Catch::Contains("malformed JSON"));
  CHECK_THAT(error_of("{}"), Catch::Contains("missing key \"objects\""));
  // A number too large for a double (found by fuzzing: it used to escape as another exception).
  CHECK_THAT(error_of("2e222222222000000000000000000000000000"), Catch::Contains("malformed JSON"));
  CHECK_THAT(error_of(R"({"objects":[]})"), Catch::Contains("at least one object"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"ids":"fancy"})"), Catch::Contains("unknown ID mode \"fancy\""));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"colour":1})"), Catch::Contains("unknown key \"colour\""));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":3}]})"), Catch::Contains("objects[0].mesh: must be a string"));
  CHECK_THAT(error_of(R"({"objects":[{"name":"x"}]})"), Catch::Contains("objects[0]: missing key \"mesh\""));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"resolution":-4})"), Catch::Contains("resolution"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"budget":0})"), Catch::Contains("budget: must be positive"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"epsilon":-1})"), Catch::Contains("epsilon"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"view":{"phi":100}})"), Catch::Contains("view.phi"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"views":4})"), Catch::Contains("views: must be 1, 2 or 3, got 4"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"edge_texels":-1})"), Catch::Contains("edge_texels: must be >= 0"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"edge_texels":"many"})"), Catch::Contains("edge_texels: must be a number"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"views":0})"), Catch::Contains("views: must be 1, 2 or 3"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"resolution":"64"})"),
             Catch::Contains("resolution: must be a number, got the string \"64\""));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"resolution":64.5})"), Catch::Contains("must be a whole number, got 64.5"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"resolution":1e20})"),
             Catch::Contains("resolution: must be within 0..32768") && Catch::Contains("got 1e+20"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"views":2.5})"), Catch::Contains("views: must be a whole number, got 2.5"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj","transform":{"translate":[1,2]}}]})"),
             Catch::Contains("translate: must be an array of 3 numbers"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj","transform":{"scale":0}}]})"), Catch::Contains("scale: must be positive"));
}

TEST_CASE("a scene whose mesh file is missing fails on loading, naming the mesh", "[scene]") {
  const Scene s = parse_scene(R"({"objects":[{"mesh":"nowhere/none.obj"}]})", "s.json", "/nonexistent-peelcd");
  CHECK_THROWS_WITH(load_objects(s), Catch::Contains("/nonexistent-peelcd/nowhere/none.obj") && Catch::Contains("no such file"));
}

// ---- the option table (peelcd/core/options.h): one definition, everything derived ----

#include "peelcd/core/options.h"
#include "peelcd/io/options_json.h"
#include "peelcd/io/costs.h"

#include <filesystem>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

TEST_CASE("every option round-trips scene -> options -> JSON -> options", "[scene][options]") {
  // A scene that sets every option to a value other than its default.
  nlohmann::json scene = {{"objects", {{{"mesh", "a.obj"}}}}};
  const DetectOptions defaults;
  for (const OptionSpec& spec : option_table()) {
    nlohmann::json value;
    switch (spec.kind) {
      case OptionSpec::Kind::boolean: value = !std::get<bool>(spec.get(defaults)); break;
      case OptionSpec::Kind::integer: value = std::get<double>(spec.get(defaults)) == spec.min ? spec.min + 1 : spec.min; break;
      case OptionSpec::Kind::number: value = std::get<double>(spec.get(defaults)) == 7.5 ? 6.25 : 7.5; break;
      case OptionSpec::Kind::choice: {
        const std::string now = std::get<std::string>(spec.get(defaults)), all = spec.choices;
        const std::string first = all.substr(0, all.find(','));
        value = first != now ? first : all.substr(all.find(',') + 1, all.find(',', all.find(',') + 1) - all.find(',') - 1);
      }
    }
    INFO(spec.key << " = " << value.dump());
    REQUIRE(check_option(spec, spec.kind == OptionSpec::Kind::choice ? OptionValue(value.get<std::string>())
                                : spec.kind == OptionSpec::Kind::boolean ? OptionValue(value.get<bool>())
                                                                         : OptionValue(value.get<double>())) == "");
    if (*spec.group) scene[spec.group][spec.key] = value;
    else scene[spec.key] = value;
  }
  const Scene s = parse_scene(scene.dump(), "all.json", ".");
  const nlohmann::json written = options_to_json(s.options);
  const DetectOptions back = options_from_json(written);
  for (const OptionSpec& spec : option_table()) {
    INFO(spec.key);
    const nlohmann::json& given = *spec.group ? scene[spec.group][spec.key] : scene[spec.key];
    CHECK(spec.get(s.options) == (given.is_boolean() ? OptionValue(given.get<bool>())
                                  : given.is_string() ? OptionValue(given.get<std::string>())
                                                      : OptionValue(given.get<double>())));  // scene -> options
    // -> JSON (kRecordedWhenSet rows: written when not the default, as every value here is)
    CHECK(written.contains(spec.key) == (spec.recorded != 0));
    if (spec.recorded) CHECK(spec.get(back) == spec.get(s.options));                         // -> options
  }
  CHECK(options_to_json(back) == written);
  // Every value the table refuses, the scene refuses with the key named, and so does the reader.
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"threads":65})"), Catch::Contains("threads: must be within 0..64"));
  CHECK_THROWS_WITH(options_from_json({{"views", 4}}), Catch::Contains("options.views: must be 1, 2 or 3"));
  CHECK_THROWS_WITH(options_from_json({{"colour", 4}}), Catch::Contains("unknown key \"colour\""));
}

TEST_CASE("the JSON Schemas list exactly the option table's recorded keys", "[scene][options]") {
  std::set<std::string> table, always;  // always: the rows written in every record (required)
  for (const OptionSpec& spec : option_table()) {
    if (spec.recorded) table.insert(spec.key);
    if (spec.recorded == 1) always.insert(spec.key);
  }
  for (const char* file : {"result.schema.json", "dump-meta.schema.json"}) {
    INFO(file);
    std::ifstream in(std::string(PEELCD_FIXTURES) + "/../docs/schema/" + file);
    REQUIRE(in);
    const nlohmann::json schema = nlohmann::json::parse(in);
    const nlohmann::json& options = schema.contains("$defs") && schema["$defs"].contains("options")
                                        ? schema["$defs"]["options"]
                                        : schema["properties"]["options"];
    std::set<std::string> listed;
    for (const auto& [key, value] : options["properties"].items()) listed.insert(key);
    CHECK(listed == table);
    if (options.contains("required")) {
      std::set<std::string> required(options["required"].begin(), options["required"].end());
      CHECK(required == always);
    }
  }
}

TEST_CASE("every GL setting round-trips scene -> options -> JSON -> options", "[scene][options][gl]") {
  // Each row of gl_option_table() set to a value that is not its default.
  nlohmann::json scene = {{"objects", {{{"mesh", "a.obj"}}}}};
  const gl::GlOptions defaults;
  for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
    const std::string now = spec.get(defaults);
    if (!*spec.choices) {
      scene[spec.key] = now != "true";
      continue;
    }
    const std::string all = spec.choices;
    std::string other;
    for (std::size_t at = 0; at <= all.size();) {
      const std::size_t end = std::min(all.find(',', at), all.size());
      if (all.substr(at, end - at) != now) {
        other = all.substr(at, end - at);
        break;
      }
      at = end + 1;
    }
    scene[spec.key] = other;
  }
  const Scene s = parse_scene(scene.dump(), "gl.json", ".");
  const nlohmann::json written = gl_options_to_json(s.gl);
  const gl::GlOptions back = gl_options_from_json(written);
  for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
    INFO(spec.key);
    CHECK(spec.get(s.gl) != spec.get(defaults));  // scene -> options
    CHECK(written.at(spec.key) == scene.at(spec.key));  // -> JSON
    CHECK(spec.get(back) == spec.get(s.gl));      // -> options
  }
  CHECK(gl_options_to_json(back) == written);
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"batch":"no"})"), Catch::Contains("batch: must be true or false"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"resolve":"fast"})"),
             Catch::Contains("resolve: unknown value \"fast\" (expected auto/gpu/host)"));
  CHECK_THROWS_WITH(gl_options_from_json({{"colour", true}}), Catch::Contains("unknown GL option \"colour\""));
}

TEST_CASE("cost models round-trip through a calibration file, and a bad or foreign one is refused", "[costs]") {
  const std::string dir = std::filesystem::temp_directory_path() / ("peelcd_costs_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  CostModels m;
  m.backend = "cpu";
  m.renderer = "peelcd CPU rasterizer";
  m.image = StageCost{0.25, 0.5, 0.75, 0.01};
  m.exact = StageCost{0.0, 0.125, 0.0, 0.0625};
  const std::string path = dir + "/costs.json";
  write_cost_models(path, m, "2026-11-25");
  const CostModels back = read_cost_models(path);
  CHECK(back.source == path);
  CHECK(back.backend == m.backend);
  CHECK(back.renderer == m.renderer);
  CHECK(back.image.view_ms == m.image.view_ms);
  CHECK(back.image.triangle_us == m.image.triangle_us);
  CHECK(back.image.texel_ns == m.image.texel_ns);
  CHECK(back.exact.triangle_us == m.exact.triangle_us);
  CHECK(back.exact.scan_us == m.exact.scan_us);
  CHECK(back.coverage.empty());  // not timed: GlOptions::coverage auto rasterizes
  m.coverage = "compute";
  write_cost_models(path, m, "2026-11-28");
  CHECK(read_cost_models(path).coverage == "compute");
  // Refused: a missing file, not JSON, another format, a negative coefficient, a coverage that is
  // not one.
  CHECK_THROWS_WITH(read_cost_models(dir + "/none.json"), Catch::Contains("none.json': cannot open"));
  const auto write = [&](const std::string& text) {
    std::ofstream(dir + "/bad.json") << text;
    return dir + "/bad.json";
  };
  CHECK_THROWS_WITH(read_cost_models(write("{")), Catch::Contains("malformed JSON"));
  CHECK_THROWS_WITH(read_cost_models(write(R"({"format":"x"})")), Catch::Contains("not a peelcd.costs/1 file"));
  CHECK_THROWS_WITH(read_cost_models(write(R"({"format":"peelcd.costs/1","backend":"cpu","renderer":"r",)"
                                           R"("image":{"view_ms":-1},"exact":{}})")),
                    Catch::Contains("image.view_ms: must be a finite number >= 0"));
  CHECK_THROWS_WITH(read_cost_models(write(R"({"format":"peelcd.costs/1","backend":"cpu","renderer":"r",)"
                                           R"("image":{},"exact":{},"coverage":"fast"})")),
                    Catch::Contains("\"coverage\" must be \"raster\" or \"compute\""));
  std::filesystem::remove_all(dir);
}

TEST_CASE("transforms that collapse geometry are refused: a tiny scale, a glTF node of scale 0", "[scene]") {
  const std::string dir = std::filesystem::temp_directory_path() / ("peelcd_collapse_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string fixtures = PEELCD_FIXTURES;
  const auto scene_with = [&](const std::string& transform) {
    return R"({"objects":[{"mesh":")" + fixtures + R"(/meshes/torus.obj","transform":)" + transform + R"(}]})";
  };
  CHECK_THAT(error_of(scene_with(R"({"scale":1e-320})")), Catch::Contains("scale: must be at least 1.2e-38"));
  // A rotation axis whose norm overflows still has a direction: the torus is turned, not lost.
  const Scene s = parse_scene(scene_with(R"({"rotate":{"axis":[1e300,1e300,0],"degrees":90}})"), "t.json", ".");
  const Mesh turned = load_objects(s).at(0).mesh;
  const Scene plain = parse_scene(scene_with(R"({"rotate":{"axis":[1,1,0],"degrees":90}})"), "t.json", ".");
  const Mesh expected = load_objects(plain).at(0).mesh;
  REQUIRE(turned.vertices.size() == expected.vertices.size());
  for (std::size_t i = 0; i < turned.vertices.size(); ++i) CHECK((turned.vertices[i] - expected.vertices[i]).norm() < 1e-12);
  // A glTF node of scale 0.
  nlohmann::json gltf = nlohmann::json::parse(std::ifstream(fixtures + "/meshes/three_box_nodes.gltf"));
  gltf["nodes"][1]["scale"] = {0, 0, 0};
  std::ofstream(dir + "/flat.gltf") << gltf.dump();
  CHECK_THROWS_WITH(load_mesh_nodes(dir + "/flat.gltf"), Catch::Contains("node 'right': its transform is singular"));
  std::filesystem::remove_all(dir);
}

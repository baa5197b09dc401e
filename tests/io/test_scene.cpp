#include "peelcd/io/error.h"
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
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"views":4})"), Catch::Contains("views: must be 1, 2 or 3"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"edge_texels":-1})"), Catch::Contains("edge_texels: must be >= 0"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"edge_texels":"many"})"), Catch::Contains("edge_texels: must be a number"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"views":0})"), Catch::Contains("views: must be 1, 2 or 3"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj"}],"views":2.5})"), Catch::Contains("views: must be 1, 2 or 3"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj","transform":{"translate":[1,2]}}]})"),
             Catch::Contains("translate: must be an array of 3 numbers"));
  CHECK_THAT(error_of(R"({"objects":[{"mesh":"a.obj","transform":{"scale":0}}]})"), Catch::Contains("scale: must be positive"));
}

TEST_CASE("a scene whose mesh file is missing fails on loading, naming the mesh", "[scene]") {
  const Scene s = parse_scene(R"({"objects":[{"mesh":"nowhere/none.obj"}]})", "s.json", "/nonexistent-peelcd");
  CHECK_THROWS_WITH(load_objects(s), Catch::Contains("/nonexistent-peelcd/nowhere/none.obj") && Catch::Contains("no such file"));
}

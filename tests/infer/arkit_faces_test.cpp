#include "infer/arkit_faces.h"

#include <string>
#include <vector>

#include "geometry/topology_fingerprint.h"
#include "tests/infer/arkit_test_support.h"

namespace retarget::test {

TEST_CASE("a take made from the face model's own weights gives the model's faces exactly", "[arkit]") {
  const FaceModel model = arkit_test_model();
  const std::vector<std::map<std::string, double>> frames = arkit_test_frames(9);
  Eigen::VectorXd identity(2);
  identity << 0.75, -1.5;
  struct Case {
    const char* name;
    ArkitTakeFormat format;
    std::string text;
  };
  const std::vector<Case> cases = {{"Live Link CSV", ArkitTakeFormat::csv, live_link_csv(frames)},
                                   {"JSON lines, ICT names", ArkitTakeFormat::jsonl, ict_jsonl(frames)}};
  for (const Case& c : cases)
    for (const bool mean_face : {true, false}) {
      INFO(c.name << (mean_face ? ", the mean face" : ", a chosen identity"));
      const ArkitFaces faces(model, mean_face ? Eigen::VectorXd() : identity);
      const Positions person = model.person(mean_face ? Eigen::VectorXd() : identity);
      CHECK(faces.person() == person);
      const ArkitTake take = parse_arkit_take(c.text, "take", c.format, faces.expression_names());
      REQUIRE(take.frames() == 9);
      for (int f = 0; f < take.frames(); ++f) {
        const Positions direct = model.expression(person, frames[f]);
        const Positions from_take = faces.frame(take, f);
        CHECK((from_take - direct).cwiseAbs().maxCoeff() == 0.0);
        CHECK((from_take - person).cwiseAbs().maxCoeff() > 0.0);  // the frame moves the face
      }
      const Mesh mesh = faces.mesh(take, 3);
      CHECK(mesh.vertices == model.expression(person, frames[3]));
      CHECK(topology_fingerprint(mesh) == topology_fingerprint(model.neutral));
      CHECK(mesh.source == "take frame 3");
    }
}

TEST_CASE("identity coefficients: parsed from --identity, checked against the model", "[arkit]") {
  const Eigen::VectorXd c = parse_identity(" 0.5, -1.25 ,2");
  REQUIRE(c.size() == 3);
  CHECK(c[0] == 0.5);
  CHECK(c[1] == -1.25);
  CHECK(c[2] == 2);
  CHECK(parse_identity("1").size() == 1);
  CHECK(error_of([] { parse_identity(""); }) ==
        "--identity: entry 1 is empty; expected comma-separated numbers like 0.5,-1.2");
  CHECK(error_of([] { parse_identity("0.5,,1"); }) ==
        "--identity: entry 2 is empty; expected comma-separated numbers like 0.5,-1.2");
  CHECK(error_of([] { parse_identity("0.5,abc"); }) == "--identity: entry 2: expected a finite number, got \"abc\"");
  CHECK(error_of([] { parse_identity("nan"); }) == "--identity: entry 1: expected a finite number, got \"nan\"");

  const FaceModel model = arkit_test_model();
  CHECK(error_of([&] { ArkitFaces(model, parse_identity("1,2,3")); }) ==
        "patch-model.yaml: 3 identity coefficients given but the model has 2 identity modes");
  // One coefficient: the second is 0.
  CHECK(ArkitFaces(model, parse_identity("1")).person() == model.neutral.vertices + model.identities[0].offset);

  // A take read for another model's names.
  const ArkitFaces faces(model);
  const ArkitTake other = parse_arkit_take("JawOpen\n1\n", "take.csv", ArkitTakeFormat::csv, {"jawOpen"});
  CHECK(error_of([&] { faces.frame(other, 0); }) ==
        "take.csv: the take was read for other expression names than those of the face model patch-model.yaml");
  const ArkitTake take = parse_arkit_take("JawOpen\n1\n", "take.csv", ArkitTakeFormat::csv, faces.expression_names());
  CHECK(error_of([&] { faces.frame(take, 1); }) == "take.csv: no frame 1 (the take has 1)");
}

TEST_CASE("check_face_model_for_bundle: vertex count, topology and units must be the bundle's", "[arkit]") {
  const FaceModel model = arkit_test_model();
  Mesh rest = human_patch();
  rest.source = "b/human_rest.obj";
  {
    LogCapture log;
    const FaceModelRestFit fit = check_face_model_for_bundle(model, rest, "cm");
    CHECK(fit.same);
    CHECK(fit.largest_difference == 0);
    CHECK(fit.rest_size > 2);
    CHECK(log.lines.empty());
    check_face_model_for_bundle(model, rest, "");  // units unknown: fine
  }
  const std::string advice = "give the face model the bundle's human dataset was made from (--face-model)";
  {
    Mesh other = quad_grid(9, 12, 2.0, 2.4);
    other.source = "b/human_rest.obj";
    CHECK(error_of([&] { check_face_model_for_bundle(model, other, "cm"); }) ==
          "patch-model.yaml: the face model has 143 vertices but the bundle's human rest b/human_rest.obj has 130; " +
              advice);
  }
  {
    // The same vertices with the faces turned around: same count, another topology.
    Mesh flipped = rest;
    for (int t = 0; t < flipped.triangle_count(); ++t) std::swap(flipped.triangles(t, 1), flipped.triangles(t, 2));
    const std::string message = error_of([&] { check_face_model_for_bundle(model, flipped, "cm"); });
    CHECK(message == "patch-model.yaml: the face model has the topology " + topology_fingerprint(model.neutral) +
                         " but the bundle's human rest b/human_rest.obj has " + topology_fingerprint(flipped) +
                         " (both have 143 vertices: other faces or another vertex order); " + advice);
  }
  CHECK(error_of([&] { check_face_model_for_bundle(model, rest, "mm"); }) ==
        "patch-model.yaml: the face model is in cm but the bundle's human side is in mm; " + advice);
  {
    LogCapture log;
    Mesh moved = rest;
    moved.vertices.col(2).array() += 0.05;
    const FaceModelRestFit fit = check_face_model_for_bundle(model, moved, "cm");
    CHECK_FALSE(fit.same);
    CHECK(fit.largest_difference == Approx(0.05));
    CHECK(log.count(log::Level::warn,
                    "patch-model.yaml: the face model's neutral is not the bundle's human rest "
                    "b/human_rest.obj (vertices up to 0.05 cm apart") == 1);
  }
}

}  // namespace retarget::test

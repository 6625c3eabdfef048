// Tests for geometry/face_model_fit.h: a face's blendshape weights from the face model.
#include "geometry/face_model_fit.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "core/error.h"
#include "separable_face_model.h"

using namespace retarget;

TEST_CASE("the face model fit gives back a blend's weights whoever the person is", "[face_fit]") {
  const FaceModel model = test::separable_face_model();
  const FaceModelFit fit(model);
  CHECK(fit.shapes() == std::vector<std::string>{"a", "b", "c"});
  for (const double id : {0.0, 1.5, -2.0}) {
    Eigen::VectorXd identity = Eigen::VectorXd::Constant(3, id);
    identity(1) = -0.5 * id;
    const Positions person = model.person(identity);
    const std::map<std::string, double> truth = {{"a", 0.7}, {"b", 0.0}, {"c", 0.35}};
    const std::map<std::string, double> w = fit.fit(model.expression(person, truth));
    for (const auto& [name, value] : truth)
      CHECK(w.at(name) == Approx(value).margin(2e-3));  // the ridge, on a small ill-conditioned model
  }
  // Weights outside the bounds are clamped to them; the rest still fits.
  const std::map<std::string, double> w = fit.fit(model.expression(model.neutral.vertices, {{"a", 1.6}, {"b", 0.5}}));
  CHECK(w.at("a") == Approx(1.0).margin(1e-3));
  CHECK(w.at("c") >= 0);
}

TEST_CASE("the face model fit names what is wrong", "[face_fit]") {
  FaceModel model = test::separable_face_model();
  const FaceModelFit fit(model);
  CHECK_THROWS_WITH(fit.fit(Positions::Zero(3, 3)), Catch::Contains("3 vertices") && Catch::Contains("36"));
  FaceFitOptions o;
  o.sweeps = 0;
  CHECK_THROWS_WITH(FaceModelFit(model, o), Catch::Contains("face_fit.sweeps"));
  model.expressions.clear();
  CHECK_THROWS_WITH(FaceModelFit(model), Catch::Contains("no expression shapes"));
}

#include "common/model/scene.h"
#include "common/render/image_metrics.h"

#include <catch2/catch.hpp>

using namespace ls;

TEST_CASE("rmse of identical images is 0 and of known images matches a hand computation", "[metrics]") {
  std::vector<glm::vec3> ref(100, glm::vec3(0.5f)), img = ref;
  // 99th percentile of 100 equal pixels of luminance 0.5: e = 2.
  REQUIRE(exposure_scale(ref) == Approx(2.0f));
  REQUIRE(rmse(ref, img, exposure_scale(ref)) == 0.0);
  img[7].x = 0.25f;  // scaled: 0.5 against 1.0, a difference of 0.5 in 1 of 300 channel values
  REQUIRE(rmse(ref, img, 2.0f) == Approx(std::sqrt(0.25 / 300.0)));
  // Values above 1 after scaling are clamped: a pixel at 10 differs from 0.5 by (1 - 1) = 0.
  img = ref;
  img[3] = glm::vec3(10.0f);
  ref[3] = glm::vec3(0.6f);
  REQUIRE(rmse(ref, img, 2.0f) == 0.0);
  REQUIRE_THROWS_AS(rmse(ref, std::vector<glm::vec3>(99), 1.0f), InputError);
}

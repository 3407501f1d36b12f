// rmse_bias (validate/bias_estimate.h) as a pure function: images with a known injected bias and
// independent noise per half, as renders of 4 and 64 samples per pixel have it, give back the bias
// within a few of their standard errors, and those standard errors are honest over many draws.
#include "validate/bias_estimate.h"

#include "common/model/scene.h"
#include "common/render/image_metrics.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace ls;

namespace {

constexpr uint32_t kWidth = 64, kHeight = 48;

// Reference and approximation over two halves of `spp` samples: expected images `base` and `base + b`
// with b drawn per pixel and channel (its RMS is `true_bias`), plus noise of variance sigma^2 / samples,
// independent per image and half.  Values stay inside [0, 1] by far, so the clamp changes nothing.
struct Synthetic {
  std::vector<glm::vec3> ref_a, img_a, ref_b, img_b;
  double true_bias = 0.0;
};

Synthetic synthetic(int spp, double bias_rms, double sigma, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> base(0.4f, 0.6f), sign(-1.0f, 1.0f);
  const int half = spp / 2;
  std::normal_distribution<float> noise(0.0f, float(sigma / std::sqrt(double(half))));
  Synthetic s;
  double sum = 0.0;
  for (uint32_t i = 0; i < kWidth * kHeight; ++i) {
    glm::vec3 expected, bias;
    for (int c = 0; c < 3; ++c) {
      expected[c] = base(rng);
      bias[c] = float(bias_rms * std::sqrt(3.0)) * sign(rng);  // uniform: mean square bias_rms^2
      sum += double(bias[c]) * double(bias[c]);
    }
    auto noisy = [&](glm::vec3 v) { return v + glm::vec3(noise(rng), noise(rng), noise(rng)); };
    s.ref_a.push_back(noisy(expected));
    s.img_a.push_back(noisy(expected + bias));
    s.ref_b.push_back(noisy(expected));
    s.img_b.push_back(noisy(expected + bias));
  }
  s.true_bias = std::sqrt(sum / (3.0 * kWidth * kHeight));
  return s;
}

BiasEstimate estimate(const Synthetic& s, int spp) {
  return estimate_bias(s.ref_a, s.img_a, s.ref_b, s.img_b, 1.0f, spp / 2, spp / 2);
}

std::vector<glm::vec3> average(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  std::vector<glm::vec3> out;
  for (size_t i = 0; i < a.size(); ++i) out.push_back(0.5f * (a[i] + b[i]));
  return out;
}

}  // namespace

TEST_CASE("rmse_bias recovers an injected bias within a few standard errors at 4 and at 64 spp", "[bias]") {
  const double sigma = 0.1, bias = 0.01;
  double stderr_at_4 = 0.0;
  for (int spp : {4, 64}) {
    INFO(spp << " spp");
    const Synthetic s = synthetic(spp, bias, sigma, 11u + uint32_t(spp));
    const BiasEstimate e = estimate(s, spp);
    INFO("true " << s.true_bias << ", estimate " << e.rmse_bias << " ± " << e.rmse_bias_stderr);
    REQUIRE(e.pixels == kWidth * kHeight);
    REQUIRE(e.rmse_bias_stderr > 0.0);
    REQUIRE(std::abs(e.rmse_bias - s.true_bias) <= 3.0 * e.rmse_bias_stderr);
    // The plain RMSE of the images over all samples carries the noise: at 4 spp far above the bias.
    const double plain = rmse(average(s.ref_a, s.ref_b), average(s.img_a, s.img_b), 1.0f);
    // The noise floor is the RMS of the noise in that difference: sigma * sqrt(2 / spp) here.
    REQUIRE(e.noise_floor == Approx(sigma * std::sqrt(2.0 / spp)).epsilon(0.05));
    REQUIRE(plain * plain == Approx(s.true_bias * s.true_bias + e.noise_floor * e.noise_floor).epsilon(0.1));
    if (spp == 4) {
      REQUIRE(plain > 4.0 * s.true_bias);
      stderr_at_4 = e.rmse_bias_stderr;
    } else {
      REQUIRE(e.rmse_bias_stderr < 0.25 * stderr_at_4);  // more samples, less noise in the estimate
      REQUIRE(e.rmse_bias_stderr < 0.1 * s.true_bias);
    }
  }
}

TEST_CASE("rmse_bias's standard error is honest: the spread over many draws matches it", "[bias]") {
  for (int spp : {4, 64}) {
    INFO(spp << " spp");
    const int draws = 120;
    double sum = 0.0, sum2 = 0.0, se_sum = 0.0;
    int within = 0;
    for (int d = 0; d < draws; ++d) {
      const Synthetic s = synthetic(spp, 0.02, 0.1, 1000u * uint32_t(spp) + uint32_t(d));
      const BiasEstimate e = estimate(s, spp);
      sum += e.rmse_bias;
      sum2 += e.rmse_bias * e.rmse_bias;
      se_sum += e.rmse_bias_stderr;
      within += std::abs(e.rmse_bias - s.true_bias) <= 2.0 * e.rmse_bias_stderr;
    }
    const double mean = sum / draws, spread = std::sqrt(sum2 / draws - mean * mean), se = se_sum / draws;
    INFO("spread " << spread << ", mean standard error " << se << ", within 2 se " << within << " of " << draws);
    REQUIRE(spread > 0.6 * se);
    REQUIRE(spread < 1.6 * se);
    REQUIRE(within >= int(0.85 * draws));
    REQUIRE(mean == Approx(0.02).epsilon(0.1));  // no drift with the noise level
  }
}

TEST_CASE("rmse_bias of images without bias: zero when equal, the mean product within its error when noisy", "[bias]") {
  const Synthetic s = synthetic(4, 0.0, 0.1, 5u);
  REQUIRE(s.true_bias == 0.0);
  const BiasEstimate e = estimate(s, 4);
  REQUIRE(std::abs(e.mean_product) <= 3.0 * e.mean_product_stderr);
  // Never negative; the standard error stays finite at zero (the root of one standard error of the mean).
  REQUIRE(e.rmse_bias >= 0.0);
  REQUIRE(std::isfinite(e.rmse_bias_stderr));
  REQUIRE(e.rmse_bias_stderr > 0.0);
  // Approximation equal to the reference in each half: exactly zero, nothing uncertain.
  const BiasEstimate same = estimate_bias(s.ref_a, s.ref_a, s.ref_b, s.ref_b, 1.0f, 2, 2);
  REQUIRE(same.rmse_bias == 0.0);
  REQUIRE(same.rmse_bias_stderr == 0.0);
  REQUIRE(same.noise_floor == 0.0);
}

TEST_CASE("rmse_bias: the scale and clamp of the RMSE, no second half, sizes that differ", "[bias]") {
  // One pixel, difference 0.5 in every channel before scaling by 0.5 and 4 after clamping to [0, 1].
  const std::vector<glm::vec3> ref{glm::vec3(0.0f)}, img{glm::vec3(0.5f)};
  REQUIRE(estimate_bias(ref, img, ref, img, 0.5f, 1, 1).rmse_bias == Approx(0.25));
  REQUIRE(estimate_bias(ref, img, ref, img, 4.0f, 1, 1).rmse_bias == Approx(1.0));
  // 1 sample per pixel: no second half, no estimate.
  REQUIRE_FALSE(estimate_bias(ref, img, ref, img, 1.0f, 1, 0).valid());
  REQUIRE_THROWS_AS(estimate_bias(ref, img, ref, {}, 1.0f, 1, 1), InputError);
}

// Sparse errors at few samples (an 8x8 image at 4 spp): every pixel where the approximation differs,
// it differs in one half only.  All products are 0; their spread is 0 too, so the estimate was
// "0 +- 0", and --spp auto stopped there as converged with an RMSE of 0.04.
TEST_CASE("rmse_bias is undetermined, not 0 +- 0, where the halves differ but never in one pixel", "[bias]") {
  std::vector<glm::vec3> ref(64, glm::vec3(0.5f)), img_a = ref, img_b = ref;
  for (size_t i = 0; i < 64; i += 2) img_a[i] = glm::vec3(0.9f);
  for (size_t i = 1; i < 64; i += 8) img_b[i] = glm::vec3(0.1f);
  const BiasEstimate e = estimate_bias(ref, img_a, ref, img_b, 1.0f, 2, 2);
  CHECK_FALSE(e.valid());
  CHECK(std::isnan(e.rmse_bias_stderr));
  CHECK(e.noise_floor > 0.0);  // the differences are still measured as noise
  // One pixel where both halves differ: an estimate again, with an error that is not 0.
  img_b[0] = glm::vec3(0.9f);
  const BiasEstimate one = estimate_bias(ref, img_a, ref, img_b, 1.0f, 2, 2);
  CHECK(one.valid());
  CHECK(one.rmse_bias > 0.0);
  CHECK(one.rmse_bias_stderr > 0.0);
}

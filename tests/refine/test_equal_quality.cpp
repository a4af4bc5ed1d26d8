// The quality figures: relMSE by its definition, and the equivalent spp recovers
// the spp of a synthetic render whose error falls exactly as c / spp, reference
// noise included.
#include "core/refine/equal_quality.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack::refine;

TEST_CASE("relMSE follows its definition with the 0.01 floor")
{
    std::vector<float> x{1.1f, 0.0f}, r{1.0f, 0.1f};
    CHECK(relative_mse(x.data(), r.data(), 2) ==
          doctest::Approx(((0.01 / 1.01) + (0.01 / 0.02)) / 2).epsilon(1e-6));
}

TEST_CASE("equivalent spp recovers the spp of Gaussian renders measured against a noisy reference")
{
    // Pixel noise of a render at s spp: sigma_1 / sqrt(s), so relMSE = c / s with c = sigma_1² / (r² + 0.01).
    std::mt19937 generator(4);
    std::normal_distribution<double> unit(0, 1);
    const int pixels = 400000;
    const double truth = 0.5, sigma_one = 0.4, reference_spp = 256;
    auto render = [&](double spp) {
        std::vector<float> image(pixels);
        for (auto& v : image)
            v = static_cast<float>(truth + sigma_one / std::sqrt(spp) * unit(generator));
        return image;
    };
    std::vector<float> reference = render(reference_spp), noisy = render(4), better = render(40);
    double c = noise_constant(relative_mse(noisy.data(), reference.data(), pixels), 4, reference_spp);
    CHECK(c == doctest::Approx(sigma_one * sigma_one / (truth * truth + 0.01)).epsilon(0.03));
    CHECK(equivalent_spp(relative_mse(better.data(), reference.data(), pixels), c, reference_spp) ==
          doctest::Approx(40).epsilon(0.06));
    CHECK(std::isinf(equivalent_spp(0.5 * c / reference_spp, c, reference_spp)));
    TimeModel model = fit_time_model(4, 0.3, 256, 10.38);
    CHECK(model.k == doctest::Approx(0.04));
    CHECK(model.t0 == doctest::Approx(0.14));
    CHECK(model.seconds(100) == doctest::Approx(4.14));
}

#include "stereodet/synth/materials.h"

namespace stereodet {

Eigen::Vector3f Rgb(double r, double g, double b) {
  return Eigen::Vector3f(static_cast<float>(r), static_cast<float>(g), static_cast<float>(b));
}

float Luma(const Eigen::Vector3f& c) { return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(); }

Eigen::Vector3f Vary(Rng& rng, const Eigen::Vector3f& c, double amount) {
  return (c * static_cast<float>(rng.Uniform(1.0 - amount, 1.0 + amount))).cwiseMin(1.0f);
}

Material MakeMaterial(Pattern pattern, const Eigen::Vector3f& albedo, float contrast,
                      float reflectance) {
  Material m;
  m.pattern = pattern;
  m.albedo = albedo;
  m.contrast = contrast;
  m.lidar_reflectance = reflectance >= 0.0f ? reflectance : 0.08f + 0.5f * Luma(albedo);
  return m;
}

Eigen::Vector3f CarColour(Rng& rng) {
  switch (rng.Categorical({0.22, 0.2, 0.18, 0.14, 0.09, 0.07, 0.05, 0.05})) {
    case 0:
      return Vary(rng, Rgb(0.72, 0.72, 0.72), 0.1);  // white
    case 1:
      return Vary(rng, Rgb(0.42, 0.43, 0.45), 0.2);  // silver
    case 2:
      return Vary(rng, Rgb(0.025, 0.025, 0.03), 0.3);  // black
    case 3:
      return Vary(rng, Rgb(0.16, 0.16, 0.17), 0.3);  // dark grey
    case 4:
      return Vary(rng, Rgb(0.05, 0.09, 0.28), 0.3);  // blue
    case 5:
      return Vary(rng, Rgb(0.45, 0.05, 0.04), 0.3);  // red
    case 6:
      return Vary(rng, Rgb(0.08, 0.18, 0.09), 0.3);  // green
    default:
      return Vary(rng, Rgb(0.5, 0.42, 0.3), 0.2);  // beige
  }
}

Eigen::Vector3f ClothColour(Rng& rng) {
  switch (rng.Categorical({0.3, 0.2, 0.2, 0.15, 0.15})) {
    case 0:
      return Vary(rng, Rgb(0.04, 0.04, 0.05), 0.4);
    case 1:
      return Vary(rng, Rgb(0.08, 0.1, 0.2), 0.4);
    case 2:
      return Vary(rng, Rgb(0.3, 0.28, 0.25), 0.4);
    case 3:
      return Vary(rng, Rgb(0.5, 0.12, 0.1), 0.4);
    default: {
      // Three named draws: the order of evaluation of function arguments is unspecified in C++,
      // and the data set must not depend on the compiler.
      const double r = rng.Uniform(0.05, 0.6);
      const double g = rng.Uniform(0.05, 0.6);
      const double b = rng.Uniform(0.05, 0.6);
      return Rgb(r, g, b);
    }
  }
}

Material ClothMaterial(Rng& rng, bool lower) {
  const double pick = rng.Uniform(0.0, 1.0);
  const double contrast = rng.Uniform(0.2, 0.35);
  Material m = MakeMaterial(Pattern::kCloth, ClothColour(rng), static_cast<float>(contrast));
  if (lower && pick < 0.3) {
    m.variant = 3;
    m.albedo = Vary(rng, Rgb(0.06, 0.09, 0.2), 0.4);
    m.lidar_reflectance = 0.08f + 0.5f * Luma(m.albedo);
  } else if (pick > 0.9) {
    m.variant = 2;
  } else if (pick > 0.75) {
    m.variant = 1;
  }
  if (m.variant == 1 || m.variant == 2) {
    m.albedo2 = ClothColour(rng);
    m.scale_m = static_cast<float>(rng.Uniform(0.03, 0.12));
  }
  return m;
}

}  // namespace stereodet

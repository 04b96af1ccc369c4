// Colours and material presets of the synthetic scenes, shared by the object builders (objects.h)
// and the street builder (scene_sampler.h). Colours are linear RGB in [0, 1].
#ifndef STEREODET_SYNTH_MATERIALS_H_
#define STEREODET_SYNTH_MATERIALS_H_

#include <Eigen/Core>

#include "stereodet/synth/random.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

// The colour (r, g, b) in single precision.
Eigen::Vector3f Rgb(double r, double g, double b);

// Rec. 709 luma of a linear RGB colour: 0.2126 r + 0.7152 g + 0.0722 b.
float Luma(const Eigen::Vector3f& c);

// `c` times a brightness factor drawn uniformly from [1 - amount, 1 + amount), each channel then
// clipped at 1.
Eigen::Vector3f Vary(Rng& rng, const Eigen::Vector3f& c, double amount);

// A material with the given pattern, albedo and fine-noise contrast (scene.h). A negative
// `reflectance` gives the LiDAR reflectance 0.08 + 0.5 Luma(albedo): the HDL-64E's 905 nm return
// tracks visible brightness loosely. The other fields keep Material's defaults.
Material MakeMaterial(Pattern pattern, const Eigen::Vector3f& albedo, float contrast,
                      float reflectance = -1.0f);

// A car paint colour drawn from roughly the mix of European city traffic (many greys, whites and
// blacks; some blue, red, green and beige).
Eigen::Vector3f CarColour(Rng& rng);

// A clothing colour: mostly dark, navy, grey-brown or red, sometimes any muted colour.
Eigen::Vector3f ClothColour(Rng& rng);

// A garment: a kCloth material (scene.h's variants) of ClothColour with fold contrast 0.2-0.35:
// plain (75 %), striped (15 %) or checked (10 %), the stripes and checks of a second
// ClothColour with a period of 3-12 cm; of the `lower` garments (trousers, skirts) 30 % are denim
// instead of plain.
Material ClothMaterial(Rng& rng, bool lower);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_MATERIALS_H_

// Procedural surface textures: band-limited value noise and the patterns of synth materials.
//
// Textures are functions of surface coordinates in metres (ground: rect x/z; box faces: the face's
// two local axes; cylinders: arc length and height), so both cameras see the same texture on the
// same surface point and block matching has true correspondences to find. Each texture is
// filtered to the pixel footprint (octaves finer than about two footprints are faded out), so far
// surfaces do not alias into per-camera noise, while near ones keep detail down to the pixel.
#ifndef STEREODET_SYNTH_TEXTURE_H_
#define STEREODET_SYNTH_TEXTURE_H_

#include <Eigen/Core>

#include "stereodet/synth/scene.h"

namespace stereodet {

// Smooth value noise in [-1, 1], one lattice cell per unit, period 256 cells.
float ValueNoise(float x, float y);

// Fractal sum of ValueNoise octaves: frequencies base_frequency * 2^k (cycles per metre),
// amplitudes gain^k, normalised to about [-1, 1]; octaves with a wavelength below 2 * footprint_m
// are dropped and those near that limit faded, up to `max_octaves`.
float FilteredFbm(float x, float y, float base_frequency, float gain, int max_octaves,
                  float footprint_m);

// Surface coordinates (metres) of a hit for texturing: for vertical faces x runs horizontally and
// y is the height above the primitive's bottom.
Eigen::Vector2f SurfaceCoordinates(const Scene& scene, const SurfaceHit& hit);

// Whether a ground point (rect x, z) lies on a painted lane marking of `road`.
bool OnRoadMarking(const Road& road, float x, float z);

// The albedo (linear RGB) at a hit seen with a pixel footprint of `footprint_m` metres.
Eigen::Vector3f SurfaceAlbedo(const Scene& scene, const SurfaceHit& hit, float footprint_m);

// Radiance of the sky in unit direction `direction` (rect frame).
Eigen::Vector3f SkyRadiance(const Lighting& light, const Eigen::Vector3f& direction);

// What paint and glass mirror in unit direction `direction` (rect frame): the sky above a skyline
// of facades and trees (its profile set by light.skyline_offset), the street below the horizon.
// No rays are cast: a distant environment, as a renderer's environment map. On a curved panel the
// mirrored direction turns along the body, so the reflection varies over it as on a real car.
Eigen::Vector3f ReflectedRadiance(const Lighting& light, const Eigen::Vector3f& direction);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_TEXTURE_H_

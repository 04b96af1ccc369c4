#include "stereodet/synth/texture.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "stereodet/synth/materials.h"
#include "stereodet/synth/random.h"

namespace stereodet {

namespace {

constexpr int kNoisePeriod = 256;

// The lattice values of ValueNoise, fixed for every run (a constant seed), built at load time (a
// namespace-scope table rather than a function-local static: no guard check in the hot loop).
using Lattice = std::array<float, kNoisePeriod * kNoisePeriod>;
Lattice MakeLattice() {
  Lattice values{};
  for (int i = 0; i < kNoisePeriod * kNoisePeriod; ++i) {
    values[i] = 2.0f * HashToUnitFloat(HashOf({0x5eed, static_cast<uint64_t>(i)})) - 1.0f;
  }
  return values;
}
const Lattice kLattice = MakeLattice();

inline float Noise(float x, float y) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int ix = static_cast<int>(fx) & (kNoisePeriod - 1);
  const int iy = static_cast<int>(fy) & (kNoisePeriod - 1);
  const int ix1 = (ix + 1) & (kNoisePeriod - 1), iy1 = (iy + 1) & (kNoisePeriod - 1);
  float tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0f - 2.0f * tx);  // smoothstep: C1 across cells
  ty = ty * ty * (3.0f - 2.0f * ty);
  const float a = kLattice[iy * kNoisePeriod + ix], b = kLattice[iy * kNoisePeriod + ix1];
  const float c = kLattice[iy1 * kNoisePeriod + ix], d = kLattice[iy1 * kNoisePeriod + ix1];
  const float top = a + (b - a) * tx;
  return top + ((c + (d - c) * tx) - top) * ty;
}

float Fract(float x) { return x - std::floor(x); }
float Clamp01(float x) { return std::clamp(x, 0.0f, 1.0f); }

// Fraction of a footprint of width 2*half_fp centred at `coord` covered by lines of `width` that
// repeat every `period` (the first centred at `phase`): a 1-D box filter, exact for one line.
float LineCoverage(float coord, float period, float phase, float width, float footprint) {
  const float half_fp = std::max(0.5f * footprint, 1e-5f);
  const float d = std::abs((Fract((coord - phase) / period + 0.5f) - 0.5f) * period);
  const float half = 0.5f * width;
  const float overlap = std::min(d + half_fp, half) - std::max(d - half_fp, -half);
  return Clamp01(overlap / (2.0f * half_fp));
}

// Fraction of a footprint centred at `coord` that lies in [lo, hi].
float IntervalCoverage(float coord, float lo, float hi, float footprint) {
  const float half_fp = std::max(0.5f * footprint, 1e-5f);
  return Clamp01((std::min(coord + half_fp, hi) - std::max(coord - half_fp, lo)) /
                 (2.0f * half_fp));
}

// Tone in [-1, 1] of lattice cell (i, j), for stones, bricks and windows.
float CellTone(float i, float j, uint64_t salt) {
  return 2.0f * HashToUnitFloat(HashOf({salt, static_cast<uint64_t>(static_cast<int64_t>(i)),
                                        static_cast<uint64_t>(static_cast<int64_t>(j))})) -
         1.0f;
}

// The colour of road dust on cars (linear RGB).
const Eigen::Vector3f kDust(0.3f, 0.28f, 0.25f);
const Eigen::Vector3f kGrime(0.1f, 0.095f, 0.085f);

// How much dust covers a car's surface point (u, v) (metres), at most `strength`: patches a metre
// across made of specks of 2-8 cm, as a film of road dust dries. Filtered to the footprint: far
// away the specks blend into their mean.
float DustFilm(float u, float v, float fp, float strength) {
  const float patches = Clamp01(0.55f + 0.9f * FilteredFbm(u + 27.0f, v + 3.0f, 1.2f, 0.5f, 3, fp));
  const float specks = Clamp01(0.5f + 1.2f * FilteredFbm(u + 3.0f, v + 57.0f, 8.0f, 0.8f, 5, fp));
  return strength * patches * specks;
}

struct FaceInfo {
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();  // surface coordinates, metres
  int axis = 1;                                  // local axis of the face normal (boxes)
  float sign = 1.0f;                             // direction of the normal along that axis
  Eigen::Vector3f local = Eigen::Vector3f::Zero();
  Eigen::Vector3f half = Eigen::Vector3f::Zero();
  // Where the shape's surface lies along each local axis through the point (boxes: -+half;
  // rounded boxes: where the line leaves the ellipsoid, within the box): the pillars, frames and
  // lamps follow a curved panel's outline.
  Eigen::Vector3f span_lo = Eigen::Vector3f::Zero();
  Eigen::Vector3f span_hi = Eigen::Vector3f::Zero();
};

FaceInfo Face(const Scene& scene, const SurfaceHit& hit) {
  FaceInfo f;
  if (hit.kind == SurfaceHit::Kind::kGround) {
    f.uv = Eigen::Vector2f(hit.point.x(), hit.point.z());
    return f;
  }
  const Primitive& p = scene.primitives[hit.primitive];
  f.local = p.ToLocal(hit.point);
  f.half = p.half_extent;
  const Eigen::Vector3f n = p.world_from_local.transpose() * hit.normal;
  const float height = p.half_extent.y() - f.local.y();  // above the primitive's bottom (y down)
  f.span_lo = -p.half_extent;
  f.span_hi = p.half_extent;
  switch (p.kind) {
    case ShapeKind::kBox:
    case ShapeKind::kRoundedBox: {  // curved panels: the face the normal mostly faces
      n.cwiseAbs().maxCoeff(&f.axis);
      f.sign = n[f.axis] >= 0.0f ? 1.0f : -1.0f;
      if (f.axis == 1) {
        f.uv = Eigen::Vector2f(f.local.x(), f.local.z());
      } else if (f.axis == 0) {
        f.uv = Eigen::Vector2f(f.local.z(), height);
      } else {
        f.uv = Eigen::Vector2f(f.local.x(), height);
      }
      break;
    }
    case ShapeKind::kCylinder:
      if (std::abs(n.y()) > 0.5f) {
        f.uv = Eigen::Vector2f(f.local.x(), f.local.z());
      } else {
        f.uv = Eigen::Vector2f(std::atan2(f.local.z(), f.local.x()) * p.half_extent.x(), height);
      }
      break;
    case ShapeKind::kEllipsoid:
      f.uv = Eigen::Vector2f(
          std::atan2(f.local.z(), f.local.x()) * 0.5f * (p.half_extent.x() + p.half_extent.z()),
          height);
      break;
  }
  if (p.kind == ShapeKind::kRoundedBox) {
    // The outline as seen along the face's axis: the ellipsoid's reach along each other axis
    // through the point, in the plane of the ellipsoid's centre across the face.
    Eigen::Vector3f q = (f.local - p.round_centre).cwiseQuotient(p.round_radii);
    q[f.axis] = 0.0f;
    const float q2 = q.squaredNorm();
    for (int a = 0; a < 3; ++a) {
      if (a == f.axis) continue;
      const float reach = p.round_radii[a] * std::sqrt(std::max(0.0f, 1.0f - (q2 - q[a] * q[a])));
      f.span_lo[a] = std::max(-p.half_extent[a], p.round_centre[a] - reach);
      f.span_hi[a] = std::min(p.half_extent[a], p.round_centre[a] + reach);
    }
  }
  f.uv += p.texture_offset;
  return f;
}

}  // namespace

float ValueNoise(float x, float y) { return Noise(x, y); }

float FilteredFbm(float x, float y, float base_frequency, float gain, int max_octaves,
                  float footprint_m) {
  float sum = 0.0f, norm = 0.0f, amplitude = 1.0f, frequency = base_frequency;
  for (int k = 0; k < max_octaves; ++k) {
    // Wavelength / footprint: full weight from 4 footprints up, none below 2.
    const float cycles_per_footprint = frequency * footprint_m;
    const float weight = Clamp01(2.0f - 4.0f * cycles_per_footprint);
    norm += amplitude;
    if (weight <= 0.0f) break;
    sum += weight * amplitude * Noise(frequency * x + 37.1f * k, frequency * y + 11.7f * k);
    // Each octave is rotated (by 36.87 degrees) and shifted so the lattices do not line up.
    const float rotated_x = 0.8f * x - 0.6f * y;
    y = 0.6f * x + 0.8f * y;
    x = rotated_x;
    amplitude *= gain;
    frequency *= 2.0f;
  }
  return norm > 0.0f ? sum / norm * 1.6f : 0.0f;
}

Eigen::Vector2f SurfaceCoordinates(const Scene& scene, const SurfaceHit& hit) {
  return Face(scene, hit).uv;
}

bool OnRoadMarking(const Road& road, float x, float z) {
  const Eigen::Vector2f rc = road.ToRoad(x, z);
  if (road.SideStreetAt(rc.y()) != nullptr) return false;
  for (const Road::Marking& m : road.markings) {
    if (std::abs(rc.x() - m.lateral_m) <= 0.5f * m.width_m) {
      if (!m.dashed || Fract(rc.y() / 9.0f) < 1.0f / 3.0f) return true;
    }
  }
  return false;
}

Eigen::Vector3f SurfaceAlbedo(const Scene& scene, const SurfaceHit& hit, float footprint_m) {
  const Material& m = scene.materials[hit.material];
  const FaceInfo f = Face(scene, hit);
  const float u = f.uv.x(), v = f.uv.y();
  const float fp = footprint_m;
  switch (m.pattern) {
    case Pattern::kPlain:
      return m.albedo * (1.0f + m.contrast * FilteredFbm(u, v, 2.0f, 0.6f, 8, fp));
    case Pattern::kAsphalt: {
      // Aggregate and grain down to the pixel, stains at the scale of a block-matching window,
      // repaired patches with sharp edges, and cracks along the zero lines of a noise field.
      const float grain = FilteredFbm(u, v, 6.0f, 0.8f, 7, fp);
      const float stains = FilteredFbm(u + 71.0f, v, 1.2f, 0.7f, 3, fp);
      const float patches =
          0.5f * Noise(0.12f * u + 91.0f, 0.12f * v) + 0.25f * Noise(0.5f * u, 0.5f * v + 13.0f);
      float tone = 1.0f + m.contrast * grain + 0.25f * stains + 0.18f * patches;
      // Repairs: in 5 x 7 m cells, one in five holds a rectangle of fresher (darker) or older
      // (lighter) asphalt, box-filtered at its edges.
      {
        const float ci = std::floor(u / 5.0f), cj = std::floor(v / 7.0f);
        const float pick = CellTone(ci, cj, 41);
        if (pick > 0.6f) {
          const float a = CellTone(ci, cj, 43), b = CellTone(ci, cj, 47);
          const float u0 = ci * 5.0f + 1.0f + 0.8f * a, u1 = u0 + 2.0f + 1.0f * b;
          const float v0 = cj * 7.0f + 1.0f + 1.0f * b, v1 = v0 + 3.0f + 1.5f * a;
          const float cover = IntervalCoverage(u, u0, u1, fp) * IntervalCoverage(v, v0, v1, fp);
          tone *= 1.0f + cover * (pick > 0.8f ? -0.22f : 0.15f);
        }
      }
      // Cracks: thin dark lines where a large-scale noise crosses zero, only in some regions.
      {
        const float crackable = Noise(0.07f * u + 3.0f, 0.07f * v + 5.0f);
        if (crackable > 0.1f) {
          constexpr float kFreq = 0.45f;
          const float n = Noise(kFreq * u + 17.0f, kFreq * v + 29.0f);
          const float distance = std::abs(n) / (1.5f * kFreq);  // metres, roughly
          const float cover = LineCoverage(distance, 1000.0f, 0.0f, 0.012f, fp);
          tone *= 1.0f - 0.55f * cover * Clamp01(4.0f * (crackable - 0.1f));
        }
      }
      Eigen::Vector3f albedo = m.albedo * std::max(0.2f, tone);
      if (hit.kind == SurfaceHit::Kind::kGround && hit.material == scene.road_material) {
        // Markings, box-filtered across their width so far lines fade instead of flickering, and
        // worn: tyres rub the paint off in blotches.
        const Eigen::Vector2f rc = scene.road.ToRoad(hit.point.x(), hit.point.z());
        float paint = 0.0f;
        // Lane lines stop at side streets.
        const bool junction = scene.road.SideStreetAt(rc.y()) != nullptr;
        for (const Road::Marking& mk : scene.road.markings) {
          if (junction) break;
          float cover = LineCoverage(rc.x(), 1000.0f, mk.lateral_m, mk.width_m, fp);
          if (cover > 0.0f && mk.dashed) cover *= LineCoverage(rc.y(), 9.0f, 1.5f, 3.0f, fp);
          paint = std::max(paint, cover);
        }
        if (paint > 0.0f) {
          const float wear = Clamp01(0.8f + 0.6f * FilteredFbm(u + 5.0f, v, 3.0f, 0.7f, 5, fp));
          const Eigen::Vector3f white = m.albedo2 * (1.0f + 0.1f * grain);
          albedo = albedo + paint * wear * (white - albedo);
        }
      }
      return albedo;
    }
    case Pattern::kPaving: {
      // Stones laid by hand (since version 6): each course (a row along v) has joints of its own
      // phase (a random bond), and the joints wander by a few per cent of a stone. A perfectly
      // regular grid of dark joints was periodic along the image rows and failed block matching's
      // uniqueness test on most sidewalks (39 % density against the road's 70 %).
      const float s = m.scale_m;
      const float vj = v + 0.06f * s * Noise(0.9f * u + 3.0f, 0.3f * v);
      const float course = std::floor(vj / s);
      const float uj = u + s * (0.5f + 0.5f * CellTone(course, 0.0f, 19)) +
                       0.06f * s * Noise(0.3f * u, 0.9f * v + 7.0f);
      // Sand-filled joints: a third of the way to the joint colour.
      const float joint = 0.35f * std::max(LineCoverage(uj, s, 0.0f, 0.012f, fp),
                                           LineCoverage(vj, s, 0.0f, 0.012f, fp));
      const float tone = CellTone(std::floor(uj / s), course, 17);
      // Stones with their own tones, concrete grain, and stains that run across the joints.
      const Eigen::Vector3f stone =
          m.albedo * (1.0f + 0.22f * tone + m.contrast * FilteredFbm(u, v, 8.0f, 0.75f, 7, fp) +
                      0.12f * FilteredFbm(u + 9.0f, v, 1.5f, 0.6f, 4, fp) +
                      0.2f * FilteredFbm(u + 5.0f, v + 3.0f, 4.0f, 0.6f, 3, fp));
      return stone + joint * (m.albedo2 - stone);
    }
    case Pattern::kFacade: {
      const float pitch = m.scale_m, floor_h = 3.1f;
      // Windows: 45% of the pitch wide, 1.5 m high from 0.9 m above each floor.
      const float wu = f.axis == 1 ? 0.0f : LineCoverage(u, pitch, 0.5f * pitch, 0.45f * pitch, fp);
      const float wv = (wu <= 0.0f || v < 1.0f) ? 0.0f : LineCoverage(v, floor_h, 1.65f, 1.5f, fp);
      const float window = wu * wv;
      Eigen::Vector3f out = Eigen::Vector3f::Zero();
      if (window < 1.0f) {
        // Plaster or render: blotches and a fine grain.
        out = m.albedo * (1.0f + m.contrast * FilteredFbm(u, v, 1.5f, 0.65f, 8, fp) +
                          0.12f * FilteredFbm(u + 3.0f, v, 10.0f, 0.7f, 5, fp));
        // Floor bands (cornices) give horizontal structure; roofs and undersides are plain.
        if (f.axis != 1) out *= 1.0f - 0.25f * LineCoverage(v, floor_h, 0.0f, 0.18f, fp);
      }
      if (window > 0.0f) {
        const float tone = CellTone(std::floor(u / pitch), std::floor(v / floor_h), 23);
        // Panes with curtains and rooms behind them, split by a mullion and a transom in the
        // window frame's colour (light).
        const Eigen::Vector3f glass =
            m.albedo2 *
            std::max(0.2f, 1.0f + 0.5f * tone + 0.6f * FilteredFbm(u, v, 2.5f, 0.7f, 6, fp));
        const float bars = std::max(LineCoverage(u, pitch, 0.5f * pitch, 0.06f, fp),
                                    LineCoverage(v, floor_h, 1.65f + 0.25f, 0.06f, fp));
        const Eigen::Vector3f pane = glass + bars * (Eigen::Vector3f(0.55f, 0.55f, 0.53f) - glass);
        out += window * (pane - out);
      }
      return out;
    }
    case Pattern::kBrick: {
      const float course = 0.077f, length = 0.25f;
      const float row = std::floor(v / course);
      const float shifted = u + (std::fmod(row, 2.0f) == 0.0f ? 0.0f : 0.5f * length);
      const float mortar = std::max(LineCoverage(v, course, 0.0f, 0.012f, fp),
                                    LineCoverage(shifted, length, 0.0f, 0.012f, fp));
      const float tone = CellTone(std::floor(shifted / length), row, 29);
      const Eigen::Vector3f brick =
          m.albedo * (1.0f + 0.15f * tone + m.contrast * FilteredFbm(u, v, 10.0f, 0.6f, 5, fp));
      return brick + mortar * (m.albedo2 - brick);
    }
    case Pattern::kFence: {
      const float gap = f.axis == 1 ? 0.0f : LineCoverage(u, m.scale_m, 0.0f, 0.3f * m.scale_m, fp);
      // Weathered boards: each slat its own tone, with a grain along it.
      const float board = CellTone(std::floor(u / m.scale_m), 0.0f, 31);
      const Eigen::Vector3f slat =
          m.albedo * (1.0f + 0.2f * board + m.contrast * FilteredFbm(u, v, 4.0f, 0.6f, 6, fp) +
                      0.15f * FilteredFbm(8.0f * u, 0.5f * v, 2.0f, 0.7f, 5, fp));
      return slat + gap * (m.albedo2 - slat);
    }
    case Pattern::kFoliage: {
      const float leaves = FilteredFbm(u, v, 5.0f, 0.75f, 7, fp);
      const float clumps = Noise(1.3f * u + 5.0f, 1.3f * v);
      const Eigen::Vector3f base = m.albedo + 0.5f * (clumps + 1.0f) * (m.albedo2 - m.albedo);
      return base * std::max(0.15f, 1.0f + m.contrast * leaves);
    }
    case Pattern::kGrass: {
      const float blades = FilteredFbm(u, v, 10.0f, 0.7f, 6, fp);
      const float soil = Clamp01(0.5f + Noise(0.3f * u, 0.3f * v + 7.0f));
      const Eigen::Vector3f base = m.albedo + soil * 0.5f * (m.albedo2 - m.albedo);
      return base * (1.0f + m.contrast * blades);
    }
    case Pattern::kCarPaint: {
      // Paint with dust and spots of dirt everywhere and road grime rising from the bottom of the
      // sides.
      const float dirt = FilteredFbm(u + 13.0f, v, 6.0f, 0.7f, 6, fp);
      const float spots =
          Clamp01(2.5f * (FilteredFbm(u + 41.0f, v + 7.0f, 9.0f, 0.75f, 5, fp) - 0.15f));
      Eigen::Vector3f paint =
          m.albedo * (1.0f + m.contrast * FilteredFbm(u, v, 3.0f, 0.6f, 6, fp) + 0.14f * dirt);
      paint += 0.35f * spots * (Eigen::Vector3f(0.2f, 0.18f, 0.15f) - paint);
      // A film of road dust in patches, in fine specks (2-8 cm; a car is rarely clean), and the
      // metallic flake of the paint: what a block matcher can hold on to on a smooth panel.
      paint *= 1.0f + 0.1f * FilteredFbm(u + 61.0f, v + 5.0f, 60.0f, 0.7f, 3, fp);
      // Light dust shows on dark paint, dark grime on light paint; on the lamps, the plate and
      // the grille too.
      const float film = DustFilm(u, v, fp, 0.45f);
      const Eigen::Vector3f& film_colour = Luma(m.albedo) > 0.25f ? kGrime : kDust;
      const auto dusty = [&](const Eigen::Vector3f& c) -> Eigen::Vector3f {
        return c + film * (film_colour - c);
      };
      const Eigen::Vector3f grime(0.08f, 0.075f, 0.065f);
      if (f.axis == 1) {
        // Bonnet and boot seams across the top.
        const float seam =
            std::max(LineCoverage(f.local.x(), 1000.0f, f.half.x() - 1.05f, 0.012f, fp),
                     LineCoverage(f.local.x(), 1000.0f, -f.half.x() + 0.75f, 0.012f, fp));
        return dusty(paint + seam * (Eigen::Vector3f(0.03f, 0.03f, 0.03f) - paint));
      }
      const float grimy = Clamp01(1.0f - v / 0.45f) * Clamp01(0.55f + 0.5f * dirt);
      paint += 0.5f * grimy * (grime - paint);
      // Bumper band at the bottom of the body.
      // Bumpers: painted, a little darker (they collect the dirt), with a black plastic strip.
      if (v < 0.16f) {
        paint *= 0.75f;
        if (v < 0.05f) paint = Eigen::Vector3f(0.06f, 0.06f, 0.065f) * (1.0f + 0.6f * dirt);
      }
      if (f.axis == 0) {
        // Front (+x) and rear (-x): lamps at the outer edges, a number plate in the middle, a
        // grille between the headlamps.
        const float z = std::abs(f.local.z()), edge = f.span_hi.z();
        const bool lamp_row = v > 0.32f && v < 0.5f;
        if (lamp_row && z > edge - 0.32f) {
          const float rim = LineCoverage(z, 1000.0f, edge - 0.3f, 0.02f, fp);
          const Eigen::Vector3f lamp = f.sign > 0.0f ? Eigen::Vector3f(0.6f, 0.6f, 0.58f)
                                                     : Eigen::Vector3f(0.4f, 0.03f, 0.03f);
          // Reflector facets behind the lens: a pattern that is not periodic.
          const float facets = FilteredFbm(z * 2.0f + 9.0f, v * 2.0f, 10.0f, 0.7f, 4, fp);
          return dusty(lamp * (1.0f - 0.6f * rim) * (1.0f + 0.15f * dirt + 0.35f * facets));
        }
        if (z < 0.26f && v > 0.18f && v < 0.29f) {
          // Characters of their own widths, 4.7 cm apart, in a band 7.5 cm high.
          const float glyph = std::floor(f.local.z() / 0.047f);
          const float stroke = 0.008f + 0.006f * (CellTone(glyph, 0.0f, 61) + 1.0f);
          const float text =
              CellTone(glyph, 1.0f, 67) > -0.7f
                  ? LineCoverage(f.local.z(), 0.047f,
                                 0.0235f * (1.0f + 0.3f * CellTone(glyph, 2.0f, 71)), stroke, fp) *
                        IntervalCoverage(v, 0.197f, 0.273f, fp)
                  : 0.0f;
          return dusty(Eigen::Vector3f(0.62f, 0.62f, 0.6f) * (1.0f - 0.85f * text));
        }
        if (f.sign > 0.0f && z < edge - 0.38f && v > 0.31f && v < 0.47f) {
          const float slat = LineCoverage(v, 0.04f, 0.0f, 0.015f, fp);
          return dusty(Eigen::Vector3f(0.03f, 0.03f, 0.035f) +
                       slat * Eigen::Vector3f(0.2f, 0.2f, 0.2f));
        }
      } else {
        // Sides: a rubbing strip, door seams and handles, dark wheel arches; on a rounded body
        // the lamps wrap round from the front and the rear.
        const float x = f.local.x();
        if (v > 0.32f && v < 0.5f && f.span_hi.x() < f.half.x() &&
            (x > f.span_hi.x() - 0.12f || x < f.span_lo.x() + 0.12f)) {
          const Eigen::Vector3f lamp =
              x > 0.0f ? Eigen::Vector3f(0.6f, 0.6f, 0.58f) : Eigen::Vector3f(0.4f, 0.03f, 0.03f);
          return dusty(lamp * (1.0f + 0.15f * dirt));
        }
        const float strip = LineCoverage(v, 1000.0f, 0.3f, 0.05f, fp);
        const float seam = LineCoverage(x, 1.05f, 0.1f, 0.012f, fp) * (v > 0.16f);
        const float handle =
            IntervalCoverage(Fract((x - 0.1f) / 1.05f) * 1.05f, 0.72f, 0.9f, fp) *
            IntervalCoverage(v, f.half.y() * 2.0f - 0.17f, f.half.y() * 2.0f - 0.12f, fp);
        paint = paint +
                std::max({strip, seam, handle}) * (Eigen::Vector3f(0.04f, 0.04f, 0.04f) - paint);
        if (m.scale_m > 0.0f) {
          const float d = std::hypot(std::abs(x) - m.scale_m, v - 0.11f);  // wheel centre
          const float arch = IntervalCoverage(d, -1.0f, 0.4f, fp);
          paint += arch * (Eigen::Vector3f(0.02f, 0.02f, 0.02f) - paint);
        }
      }
      return dusty(paint);
    }
    case Pattern::kGlass: {
      // Through the glass: seats, headrests and the far side, as mid-frequency dark noise.
      Eigen::Vector3f glass =
          m.albedo * std::max(0.2f, 1.0f + m.contrast * FilteredFbm(u, v, 3.0f, 0.6f, 6, fp));
      // Seats, headrests and the dashboard as lighter shapes behind the tint, and dust on the
      // glass.
      glass *= 1.0f + 1.5f * Clamp01(FilteredFbm(u + 17.0f, v + 9.0f, 6.0f, 0.75f, 5, fp)) +
               0.5f * FilteredFbm(u + 5.0f, v + 31.0f, 12.0f, 0.7f, 4, fp);
      // Headrests: rounded lighter shapes every 0.55 m across the lower part of the pane.
      {
        const float cell = std::floor(u / 0.55f);
        const float du = (Fract(u / 0.55f) - 0.5f) * 0.55f / 0.13f;
        const float dv = (v - 0.18f - 0.04f * CellTone(cell, 0.0f, 53)) / 0.11f;
        const float r2 = du * du + dv * dv;
        const float rest = IntervalCoverage(std::sqrt(r2), -1.0f, 1.0f, fp / 0.12f);
        glass += rest * (1.0f + 0.3f * CellTone(cell, 1.0f, 59)) *
                 (Eigen::Vector3f(0.12f, 0.115f, 0.11f) - glass);
      }
      glass += DustFilm(u + 40.0f, v, fp, 0.25f) * (kDust - glass);
      float frame = 0.0f;
      if (f.axis == 2) {
        // Sides: A, B and C pillars and the frame at the sill, in the body colour.
        // On a rounded cabin the A and C pillars follow the glass's outline at this height.
        const float x = f.local.x(), hx = f.half.x();
        const float front = f.span_hi.x(), rear = f.span_lo.x();
        frame = std::max({IntervalCoverage(x, front - 0.14f, front + 1.0f, fp),
                          IntervalCoverage(x, rear - 1.0f, rear + 0.18f, fp),
                          IntervalCoverage(x, -0.05f * hx - 0.06f, -0.05f * hx + 0.06f, fp),
                          IntervalCoverage(v, -1.0f, 0.05f, fp)});
      } else if (f.axis == 0) {
        const float z = std::abs(f.local.z());
        // Windscreen and rear window: A or C pillars at the sides, a frame at the bottom.
        frame = std::max(IntervalCoverage(z, f.span_hi.z() - 0.13f, f.span_hi.z() + 1.0f, fp),
                         IntervalCoverage(v, -1.0f, 0.07f, fp));
      }
      return glass + frame * (m.albedo2 - glass);
    }
    case Pattern::kWheel: {
      // The end faces of a wheel (a cylinder on its local y axis): rim with spokes and hub inside
      // 62% of the radius, tyre sidewall outside; the tread elsewhere.
      const Primitive& p = scene.primitives[hit.primitive];
      const Eigen::Vector3f n = p.world_from_local.transpose() * hit.normal;
      Eigen::Vector3f tyre = m.albedo * (1.0f + m.contrast * FilteredFbm(u, v, 8.0f, 0.6f, 5, fp));
      const float radius = p.half_extent.x();
      if (std::abs(n.y()) <= 0.5f) {
        // The tread: blocks between transverse grooves every 3 cm of arc and two circumferential
        // grooves; grey with road dust on the blocks.
        const float width = 2.0f * p.half_extent.y();
        const float groove = std::max({LineCoverage(u, 0.03f, 0.0f, 0.008f, fp),
                                       LineCoverage(v, 1000.0f, 0.33f * width, 0.012f, fp),
                                       LineCoverage(v, 1000.0f, 0.67f * width, 0.012f, fp)});
        return tyre * (1.6f - 1.1f * groove);
      }
      // The sidewall: a ring of lettering at 80-90 % of the radius.
      const float rho_wall = std::hypot(f.local.x(), f.local.z());
      if (rho_wall > 0.8f * radius && rho_wall < 0.9f * radius) {
        const float arc = std::atan2(f.local.z(), f.local.x()) * rho_wall;
        const float glyph = std::floor(arc / 0.025f);
        if (CellTone(glyph, 0.0f, 73) > -0.2f) {
          tyre *= 1.0f + 1.2f * LineCoverage(arc, 0.025f, 0.0125f, 0.006f, fp);
        }
      }
      const float rho = rho_wall;
      const float rim_cover = IntervalCoverage(rho, -1.0f, 0.62f * radius, fp);
      if (rim_cover <= 0.0f) return tyre;
      // Five spokes; their contrast fades once the spoke period at this radius nears the footprint.
      const float theta = std::atan2(f.local.z(), f.local.x());
      const float period = 2.0f * static_cast<float>(M_PI) * std::max(rho, 1e-3f) / 5.0f;
      const float fade = Clamp01(2.0f - 4.0f * fp / period);
      const float spoke = 0.5f + 0.5f * std::cos(5.0f * theta);
      const float hub = IntervalCoverage(rho, -1.0f, 0.16f * radius, fp);
      const float metal = std::max(hub, 0.55f + fade * (Clamp01(3.0f * spoke - 1.0f) - 0.55f));
      const Eigen::Vector3f rim = m.albedo2 * (0.15f + 0.85f * metal);
      return tyre + rim_cover * (rim - tyre);
    }
    case Pattern::kCloth: {
      const float folds = FilteredFbm(u, v, 4.0f, 0.6f, 6, fp);
      Eigen::Vector3f cloth = m.albedo;
      switch (m.variant) {
        case 1:  // stripes across the garment
          cloth += LineCoverage(v, m.scale_m, 0.0f, 0.45f * m.scale_m, fp) * (m.albedo2 - cloth);
          break;
        case 2: {  // checks: two crossing sets of bands, darker where they cross
          const float a = LineCoverage(u, m.scale_m, 0.0f, 0.4f * m.scale_m, fp);
          const float b = LineCoverage(v, m.scale_m, 0.0f, 0.4f * m.scale_m, fp);
          cloth += std::max(a, b) * (m.albedo2 - cloth);
          cloth *= 1.0f - 0.3f * a * b;
          break;
        }
        case 3: {  // denim: a diagonal twill of 3 mm, faded in patches
          const float twill = LineCoverage(u + v, 0.006f, 0.0f, 0.003f, fp);
          const float fade = Clamp01(0.5f + FilteredFbm(u + 3.0f, v + 8.0f, 2.5f, 0.6f, 4, fp));
          cloth *= 1.0f + 0.25f * twill + 0.5f * fade;
          break;
        }
        default:
          break;
      }
      // Folds, and the weave and seams of the fabric at a few centimetres.
      const float weave = FilteredFbm(u + 23.0f, v + 7.0f, 16.0f, 0.7f, 4, fp);
      return cloth * (1.0f + m.contrast * (folds + 0.7f * weave));
    }
  }
  return m.albedo;
}

Eigen::Vector3f SkyRadiance(const Lighting& light, const Eigen::Vector3f& direction) {
  const float elevation = std::max(0.0f, -direction.y());  // sin of the elevation (y is down)
  Eigen::Vector3f sky =
      light.sky_horizon + std::sqrt(elevation) * (light.sky_zenith - light.sky_horizon);
  const float to_sun = std::max(0.0f, direction.dot(light.to_sun));
  sky += light.sun * (0.08f * std::pow(to_sun, 16.0f));
  if (light.cloudiness > 0.0f && elevation > 0.01f) {
    // Clouds on a plane above the camera: texture coordinates by central projection.
    const float scale = 1.0f / (elevation + 0.05f);
    const float x = 2.0f * direction.x() * scale, z = 2.0f * direction.z() * scale;
    const float c = 0.6f * Noise(x, z) + 0.3f * Noise(2.1f * x + 3.0f, 2.1f * z) +
                    0.15f * Noise(4.3f * x, 4.3f * z + 9.0f);
    const float cover = Clamp01((c + 1.2f * light.cloudiness - 0.6f) * 2.0f);
    sky += cover * (Eigen::Vector3f(0.95f, 0.95f, 0.97f) - sky);
  }
  return sky;
}

Eigen::Vector3f ReflectedRadiance(const Lighting& light, const Eigen::Vector3f& direction) {
  const float elevation = -direction.y();  // sine of the elevation (y is down)
  // Azimuth in radians times 8: the skyline's features are a few degrees wide.
  const float a = 8.0f * std::atan2(direction.x(), direction.z()) + light.skyline_offset;
  if (elevation < 0.0f) {
    // The road and the pavements, lit by the sky and the sun; darker towards the nadir (the car's
    // own shadow and the street under it).
    const float tone = 0.12f + 0.05f * Noise(3.0f * a, 40.0f * elevation) +
                       0.06f * Clamp01(1.0f + 4.0f * elevation);
    return tone * (light.sky_ambient + 0.5f * light.sun);
  }
  // Facades and trees around the street, up to 10-35 degrees, with gaps of sky between them.
  const float skyline =
      0.1f + 0.25f * Clamp01(0.5f + 0.8f * Noise(a, 3.0f)) + 0.04f * Noise(5.0f * a, 9.0f);
  if (elevation < skyline) {
    const float building = Clamp01(0.5f + 2.0f * Noise(0.5f * a + 11.0f, 1.0f));
    // Windows: columns in azimuth, rows in elevation; foliage: plain noise.
    const float windows = (Fract(4.0f * a) < 0.55f) * (Fract(40.0f * elevation) < 0.6f);
    const float facade = 0.35f + 0.2f * Noise(2.0f * a, 7.0f) - 0.22f * windows;
    const float foliage = 0.18f + 0.1f * Noise(6.0f * a, 60.0f * elevation);
    const float tone = building * facade + (1.0f - building) * foliage;
    return tone * (light.sky_ambient + 0.4f * light.sun);
  }
  return SkyRadiance(light, direction);
}

}  // namespace stereodet

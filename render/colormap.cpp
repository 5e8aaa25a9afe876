// Colour maps, written out by hand as key points (linear interpolation between them).
// turbo: a rainbow with monotonic lightness in each half, reads well on a dark
// background; viridis: perceptually uniform, for colour-blind safe figures; inferno:
// perceptually uniform from black through red to yellow (prints well in grey too); gray:
// lightness only, for figures that will be printed in black and white.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include "render/renderer.h"

namespace ravel::render {

namespace {

constexpr float kTurbo[][3] = {{0.19f, 0.07f, 0.23f}, {0.27f, 0.44f, 0.92f}, {0.15f, 0.69f, 0.98f},
                               {0.10f, 0.87f, 0.78f}, {0.30f, 0.98f, 0.49f}, {0.64f, 0.99f, 0.24f},
                               {0.89f, 0.87f, 0.21f}, {0.99f, 0.65f, 0.15f}, {0.94f, 0.38f, 0.07f},
                               {0.78f, 0.16f, 0.02f}, {0.48f, 0.02f, 0.01f}};

constexpr float kViridis[][3] = {{0.267f, 0.005f, 0.329f}, {0.253f, 0.265f, 0.530f}, {0.164f, 0.471f, 0.558f},
                                 {0.135f, 0.659f, 0.518f}, {0.478f, 0.821f, 0.318f}, {0.993f, 0.906f, 0.144f}};

constexpr float kInferno[][3] = {{0.001f, 0.000f, 0.014f}, {0.120f, 0.047f, 0.282f}, {0.327f, 0.060f, 0.430f},
                                 {0.522f, 0.134f, 0.419f}, {0.715f, 0.215f, 0.330f}, {0.878f, 0.341f, 0.200f},
                                 {0.976f, 0.540f, 0.039f}, {0.983f, 0.770f, 0.180f}, {0.988f, 0.998f, 0.645f}};

constexpr float kGray[][3] = {{0.10f, 0.10f, 0.10f}, {0.95f, 0.95f, 0.95f}};

template <int N>
Vec3 sample(const float (&table)[N][3], float t) {
  if (!(t >= 0)) t = 0;  // also catches NaN
  t = std::min(t, 1.0f) * (N - 1);
  const int i = std::min(static_cast<int>(t), N - 2);
  const float f = t - i;
  return {table[i][0] + f * (table[i + 1][0] - table[i][0]), table[i][1] + f * (table[i + 1][1] - table[i][1]),
          table[i][2] + f * (table[i + 1][2] - table[i][2])};
}

}  // namespace

Vec3 colormap(ColorMap map, float t) {
  switch (map) {
    case ColorMap::viridis:
      return sample(kViridis, t);
    case ColorMap::inferno:
      return sample(kInferno, t);
    case ColorMap::gray:
      return sample(kGray, t);
    case ColorMap::turbo:
      break;
  }
  return sample(kTurbo, t);
}

const char* to_string(ColorMap m) {
  switch (m) {
    case ColorMap::turbo:
      return "turbo";
    case ColorMap::viridis:
      return "viridis";
    case ColorMap::inferno:
      return "inferno";
    case ColorMap::gray:
      return "gray";
  }
  return "?";
}

bool parse_color_map(const std::string& name, ColorMap* out) {
  for (ColorMap m : {ColorMap::turbo, ColorMap::viridis, ColorMap::inferno, ColorMap::gray})
    if (name == to_string(m)) {
      if (out) *out = m;
      return true;
    }
  return false;
}

const char* to_string(ColorField f) {
  switch (f) {
    case ColorField::strain:
      return "strain";
    case ColorField::velocity:
      return "velocity";
    case ColorField::sliding:
      return "sliding";
    case ColorField::friction:
      return "friction";
  }
  return "?";
}

namespace {
constexpr ColorField kColorFields[] = {ColorField::strain, ColorField::velocity, ColorField::sliding,
                                       ColorField::friction};
}  // namespace

bool parse_color_field(const std::string& name, ColorField* out) {
  for (ColorField f : kColorFields)
    if (name == to_string(f)) {
      *out = f;
      return true;
    }
  return false;
}

std::string color_field_names() {
  std::string s;
  const std::size_t n = std::size(kColorFields);
  for (std::size_t i = 0; i < n; ++i)
    s += (i == 0 ? "" : i + 1 == n ? " or " : ", ") + std::string(to_string(kColorFields[i]));
  return s;
}

const char* field_title(ColorField f) {
  switch (f) {
    case ColorField::strain:
      return "strain / failure strain";
    case ColorField::velocity:
      return "yarn speed (m/s)";
    case ColorField::sliding:
      return "sliding speed (m/s)";
    case ColorField::friction:
      return "friction heat (J/g)";
  }
  return "";
}

}  // namespace ravel::render

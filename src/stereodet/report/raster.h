// PNG files rasterized from SVG text with librsvg and cairo (Debian librsvg2-dev), so that the PNG
// of a figure is the same drawing as its SVG. Built only where pkg-config finds librsvg-2.0;
// elsewhere PngFromSvgAvailable() is false and WritePngFromSvg throws.
#ifndef STEREODET_REPORT_RASTER_H_
#define STEREODET_REPORT_RASTER_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace stereodet {

// Whether PNG files can be written: built with librsvg's headers and librsvg-2.so.2 loads.
bool PngFromSvgAvailable();

// Rasterizes the SVG document `svg` at `scale` times its size in px (2: 960 x 680 px for a 480 x
// 340 figure) on a white background and writes it to `path` as PNG, atomically. Throws
// std::invalid_argument for scale outside (0, 8], std::runtime_error naming the path if librsvg
// cannot read the SVG, the file cannot be written, or the build has no librsvg.
void WritePngFromSvg(const std::filesystem::path& path, const std::string& svg, double scale = 2);

// The SVG rasterized as WritePngFromSvg draws it, as pixels: row-major, 0xRRGGBB each. For tests
// of what a figure or view shows where. Throws what WritePngFromSvg throws.
struct RasterImage {
  int width = 0, height = 0;
  std::vector<uint32_t> rgb;
  uint32_t At(int x, int y) const { return rgb[static_cast<size_t>(y) * width + x]; }
};
RasterImage RasterizeSvg(const std::string& svg, double scale = 1);

}  // namespace stereodet

#endif  // STEREODET_REPORT_RASTER_H_

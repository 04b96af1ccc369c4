#include "stereodet/report/raster.h"

#include <cmath>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

#ifdef STEREODET_HAVE_RSVG
#include <cairo.h>
#include <librsvg/rsvg.h>
#endif

namespace stereodet {

bool PngFromSvgAvailable() {
#ifdef STEREODET_HAVE_RSVG
  return true;
#else
  return false;
#endif
}

void WritePngFromSvg(const std::filesystem::path& path, const std::string& svg, double scale) {
  STEREODET_CHECK(scale > 0 && scale <= 8) << "PNG scale " << scale << " is not in (0, 8]";
#ifdef STEREODET_HAVE_RSVG
  GError* error = nullptr;
  RsvgHandle* handle =
      rsvg_handle_new_from_data(reinterpret_cast<const guint8*>(svg.data()), svg.size(), &error);
  if (handle == nullptr) {
    const std::string message = error != nullptr ? error->message : "unknown error";
    if (error != nullptr) g_error_free(error);
    STEREODET_THROW_IO() << path.string() << ": librsvg cannot read the SVG: " << message;
  }
  gdouble width = 0, height = 0;
  if (!rsvg_handle_get_intrinsic_size_in_pixels(handle, &width, &height)) {
    g_object_unref(handle);
    STEREODET_THROW_IO() << path.string() << ": the SVG has no size in px";
  }
  const int w = static_cast<int>(std::ceil(width * scale));
  const int h = static_cast<int>(std::ceil(height * scale));
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  const RsvgRectangle viewport = {0, 0, width * scale, height * scale};
  const gboolean rendered = rsvg_handle_render_document(handle, cr, &viewport, &error);
  cairo_destroy(cr);
  g_object_unref(handle);
  std::string message;
  if (!rendered) {
    message = error != nullptr ? error->message : "unknown error";
    if (error != nullptr) g_error_free(error);
  }
  cairo_status_t status = CAIRO_STATUS_SUCCESS;
  AtomicPath out(path);
  if (rendered) status = cairo_surface_write_to_png(surface, out.temp_path().c_str());
  cairo_surface_destroy(surface);
  STEREODET_CHECK_IO(rendered) << path.string() << ": librsvg cannot draw the SVG: " << message;
  STEREODET_CHECK_IO(status == CAIRO_STATUS_SUCCESS)
      << path.string() << ": cannot write the PNG: " << cairo_status_to_string(status);
  out.Commit();
#else
  (void)svg;
  STEREODET_THROW_IO() << path.string()
                       << ": this build has no PNG output (librsvg2-dev was not found)";
#endif
}

}  // namespace stereodet

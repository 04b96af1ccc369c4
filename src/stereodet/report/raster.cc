#include "stereodet/report/raster.h"

#include <cmath>
#include <mutex>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

#ifdef STEREODET_HAVE_RSVG
#include <cairo.h>
#include <dlfcn.h>
#include <librsvg/rsvg.h>
#endif

namespace stereodet {

#ifdef STEREODET_HAVE_RSVG
namespace {

// librsvg (with cairo, pango, glib: 44 shared libraries) is loaded with dlopen() when the first PNG
// is written, not linked: linked, it made every `stereodet` start (`stereodet info`, `--version`)
// load them, 20 ms instead of 3 ms and 13 MB instead of 5 MB. Only the headers are used at build
// time; the functions below are looked up in librsvg and the libraries it depends on.
struct Rsvg {
  bool loaded = false;
  std::string error;  // why not loaded
  decltype(&rsvg_handle_new_from_stream_sync) new_from_stream = nullptr;
  decltype(&g_memory_input_stream_new_from_data) memory_stream = nullptr;
  decltype(&rsvg_handle_get_intrinsic_size_in_pixels) intrinsic_size = nullptr;
  decltype(&rsvg_handle_render_document) render_document = nullptr;
  decltype(&g_object_unref) object_unref = nullptr;
  decltype(&g_error_free) error_free = nullptr;
  decltype(&cairo_image_surface_create) surface_create = nullptr;
  decltype(&cairo_create) create = nullptr;
  decltype(&cairo_set_source_rgb) set_source_rgb = nullptr;
  decltype(&cairo_paint) paint = nullptr;
  decltype(&cairo_destroy) destroy = nullptr;
  decltype(&cairo_surface_write_to_png) write_to_png = nullptr;
  decltype(&cairo_surface_destroy) surface_destroy = nullptr;
  decltype(&cairo_status_to_string) status_to_string = nullptr;
  decltype(&cairo_surface_flush) surface_flush = nullptr;
  decltype(&cairo_image_surface_get_data) surface_data = nullptr;
  decltype(&cairo_image_surface_get_stride) surface_stride = nullptr;
  decltype(&cairo_image_surface_get_width) surface_width = nullptr;
  decltype(&cairo_image_surface_get_height) surface_height = nullptr;
};

template <typename F>
bool Find(void* library, const char* name, F& f, std::string& error) {
  f = reinterpret_cast<F>(dlsym(library, name));
  if (f == nullptr && error.empty()) error = std::string("no symbol ") + name;
  return f != nullptr;
}

const Rsvg& LoadRsvg() {
  static Rsvg rsvg;
  static std::once_flag once;
  std::call_once(once, [] {
    void* library = dlopen("librsvg-2.so.2", RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
      const char* e = dlerror();
      rsvg.error = e != nullptr ? e : "dlopen failed";
      return;
    }
    std::string& e = rsvg.error;
    bool ok = Find(library, "rsvg_handle_new_from_stream_sync", rsvg.new_from_stream, e);
    ok &= Find(library, "g_memory_input_stream_new_from_data", rsvg.memory_stream, e);
    ok &= Find(library, "rsvg_handle_get_intrinsic_size_in_pixels", rsvg.intrinsic_size, e);
    ok &= Find(library, "rsvg_handle_render_document", rsvg.render_document, e);
    ok &= Find(library, "g_object_unref", rsvg.object_unref, e);
    ok &= Find(library, "g_error_free", rsvg.error_free, e);
    ok &= Find(library, "cairo_image_surface_create", rsvg.surface_create, e);
    ok &= Find(library, "cairo_create", rsvg.create, e);
    ok &= Find(library, "cairo_set_source_rgb", rsvg.set_source_rgb, e);
    ok &= Find(library, "cairo_paint", rsvg.paint, e);
    ok &= Find(library, "cairo_destroy", rsvg.destroy, e);
    ok &= Find(library, "cairo_surface_write_to_png", rsvg.write_to_png, e);
    ok &= Find(library, "cairo_surface_destroy", rsvg.surface_destroy, e);
    ok &= Find(library, "cairo_status_to_string", rsvg.status_to_string, e);
    ok &= Find(library, "cairo_surface_flush", rsvg.surface_flush, e);
    ok &= Find(library, "cairo_image_surface_get_data", rsvg.surface_data, e);
    ok &= Find(library, "cairo_image_surface_get_stride", rsvg.surface_stride, e);
    ok &= Find(library, "cairo_image_surface_get_width", rsvg.surface_width, e);
    ok &= Find(library, "cairo_image_surface_get_height", rsvg.surface_height, e);
    rsvg.loaded = ok;  // the library stays loaded for the process
  });
  return rsvg;
}

}  // namespace
#endif

bool PngFromSvgAvailable() {
#ifdef STEREODET_HAVE_RSVG
  return LoadRsvg().loaded;
#else
  return false;
#endif
}

#ifdef STEREODET_HAVE_RSVG
namespace {

// The SVG drawn at `scale` on white; the caller destroys the surface. `what` names the output in
// messages.
cairo_surface_t* Render(const Rsvg& r, const std::string& what, const std::string& svg,
                        double scale) {
  GError* error = nullptr;
  // Without limits: libxml2 refuses a text node over 10 MB by default, and a figure that overlays
  // many models carries more curve data than that in its <metadata>. The SVGs are this module's
  // own output, not untrusted input.
  GInputStream* stream = r.memory_stream(svg.data(), static_cast<gssize>(svg.size()), nullptr);
  RsvgHandle* handle =
      r.new_from_stream(stream, nullptr, RSVG_HANDLE_FLAG_UNLIMITED, nullptr, &error);
  r.object_unref(stream);
  if (handle == nullptr) {
    const std::string message = error != nullptr ? error->message : "unknown error";
    if (error != nullptr) r.error_free(error);
    STEREODET_THROW_IO() << what << ": librsvg cannot read the SVG: " << message;
  }
  gdouble width = 0, height = 0;
  if (!r.intrinsic_size(handle, &width, &height)) {
    r.object_unref(handle);
    STEREODET_THROW_IO() << what << ": the SVG has no size in px";
  }
  const int w = static_cast<int>(std::ceil(width * scale));
  const int h = static_cast<int>(std::ceil(height * scale));
  cairo_surface_t* surface = r.surface_create(CAIRO_FORMAT_RGB24, w, h);
  cairo_t* cr = r.create(surface);
  r.set_source_rgb(cr, 1, 1, 1);
  r.paint(cr);
  const RsvgRectangle viewport = {0, 0, width * scale, height * scale};
  const gboolean rendered = r.render_document(handle, cr, &viewport, &error);
  r.destroy(cr);
  r.object_unref(handle);
  if (!rendered) {
    const std::string message = error != nullptr ? error->message : "unknown error";
    if (error != nullptr) r.error_free(error);
    r.surface_destroy(surface);
    STEREODET_THROW_IO() << what << ": librsvg cannot draw the SVG: " << message;
  }
  return surface;
}

const Rsvg& LoadedRsvg(const std::string& what) {
  const Rsvg& r = LoadRsvg();
  STEREODET_CHECK_IO(r.loaded) << what << ": cannot load librsvg (" << r.error
                               << "); install librsvg2-2";
  return r;
}

}  // namespace
#endif

void WritePngFromSvg(const std::filesystem::path& path, const std::string& svg, double scale) {
  STEREODET_CHECK(scale > 0 && scale <= 8) << "PNG scale " << scale << " is not in (0, 8]";
#ifdef STEREODET_HAVE_RSVG
  const Rsvg& r = LoadedRsvg(path.string());
  cairo_surface_t* surface = Render(r, path.string(), svg, scale);
  AtomicPath out(path);
  const cairo_status_t status = r.write_to_png(surface, out.temp_path().c_str());
  r.surface_destroy(surface);
  STEREODET_CHECK_IO(status == CAIRO_STATUS_SUCCESS)
      << path.string() << ": cannot write the PNG: " << r.status_to_string(status);
  out.Commit();
#else
  (void)svg;
  STEREODET_THROW_IO() << path.string()
                       << ": this build has no PNG output (librsvg2-dev was not found)";
#endif
}

RasterImage RasterizeSvg(const std::string& svg, double scale) {
  STEREODET_CHECK(scale > 0 && scale <= 8) << "raster scale " << scale << " is not in (0, 8]";
#ifdef STEREODET_HAVE_RSVG
  const Rsvg& r = LoadedRsvg("SVG raster");
  cairo_surface_t* surface = Render(r, "SVG raster", svg, scale);
  r.surface_flush(surface);
  RasterImage image;
  const unsigned char* data = r.surface_data(surface);
  const int stride = r.surface_stride(surface);
  // CAIRO_FORMAT_RGB24: one native-endian 32-bit word per pixel, 0x00RRGGBB.
  image.width = r.surface_width(surface);
  image.height = r.surface_height(surface);
  image.rgb.resize(static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) {
    const auto* row = reinterpret_cast<const uint32_t*>(data + static_cast<size_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      image.rgb[static_cast<size_t>(y) * image.width + x] = row[x] & 0xFFFFFFu;
    }
  }
  r.surface_destroy(surface);
  return image;
#else
  (void)svg;
  STEREODET_THROW_IO() << "SVG raster: this build has no librsvg (librsvg2-dev was not found)";
#endif
}

}  // namespace stereodet

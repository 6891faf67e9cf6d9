#include "stitch_command.h"

#include <png.h>

#include <algorithm>
#include <fstream>
#include <iostream>

#include "atlas/stitch_seams.h"
#include "core/error.h"
#include "intake/read_mesh_file.h"

namespace qgp::cli {
namespace {

// An 8-bit RGB or RGBA PNG (grey and palette images are widened to RGB) as texels in [0, 1].
AtlasImage read_png(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str()))
    throw Error(ErrorCode::UnreadableFile, "cannot read '" + path + "': " + png.message);
  png.format = (png.format & PNG_FORMAT_FLAG_ALPHA) ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  std::vector<png_byte> bytes(PNG_IMAGE_SIZE(png));
  const int stride = -static_cast<int>(PNG_IMAGE_ROW_STRIDE(png));  // negative: bottom row first
  if (!png_image_finish_read(&png, nullptr, bytes.data(), stride, nullptr)) {
    const std::string why = png.message;
    png_image_free(&png);
    throw Error(ErrorCode::UnreadableFile, "cannot read '" + path + "': " + why);
  }
  AtlasImage image{static_cast<int>(png.width),
                   static_cast<int>(png.height),
                   static_cast<int>(PNG_IMAGE_PIXEL_CHANNELS(png.format)),
                   {}};
  image.texels.resize(bytes.size());
  for (size_t i = 0; i < bytes.size(); ++i) image.texels[i] = bytes[i] / 255.0f;
  return image;
}

void write_png(const std::string& path, const AtlasImage& image) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = image.width;
  png.height = image.height;
  png.format = image.channels == 4 ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  std::vector<png_byte> bytes(image.texels.size());
  for (size_t i = 0; i < bytes.size(); ++i)
    bytes[i] = static_cast<png_byte>(std::clamp(image.texels[i], 0.0f, 1.0f) * 255.0f + 0.5f);
  const int stride = -static_cast<int>(PNG_IMAGE_ROW_STRIDE(png));
  if (!png_image_write_to_file(&png, path.c_str(), 0, bytes.data(), stride, nullptr))
    throw std::runtime_error("cannot write '" + path + "': " + png.message);
}

// The per-corner atlas coordinates of an OBJ file's faces; refused when a corner has none.
std::vector<std::array<double, 2>> corner_atlas_coordinates(const PolygonSoup& soup, const std::string& path) {
  if (soup.corner_texcoord.empty())
    throw Error(ErrorCode::InvalidArgument, "'" + path + "' has no texture coordinates (vt): no atlas to stitch");
  std::vector<std::array<double, 2>> uv(soup.corner_texcoord.size());
  for (size_t c = 0; c < uv.size(); ++c) {
    if (soup.corner_texcoord[c] < 0)
      throw Error(ErrorCode::InvalidArgument,
                  "'" + path + "': face corner " + std::to_string(c) + " has no texture coordinate (vt)");
    uv[c] = soup.texcoords[soup.corner_texcoord[c]];
  }
  return uv;
}

void print_summary(const StitchReport& r, const std::string& output) {
  std::cout << "stitched " << r.seam_edges << " seam edges between " << r.charts << " charts: " << r.seam_texels
            << " texels from across a seam, " << r.filled_texels << " other empty texels filled; wrote " << output
            << "\n";
  if (r.unmatched_seam_edges > 0)
    std::cout << "warning: " << r.unmatched_seam_edges
              << " seam edges do not map texels onto texels (not a grid atlas there); filled as borders\n";
}

}  // namespace

int run_stitch(const StitchCommand& command) {
  StitchReport result;
  try {
    const PolygonSoup soup = read_mesh_file(command.atlas);
    const std::vector<std::array<double, 2>> uv = corner_atlas_coordinates(soup, command.atlas);
    AtlasImage image = read_png(command.image);
    result = stitch_seams(soup, uv, image);
    write_png(command.output, image);
  } catch (const Error& e) {
    std::cerr << "qgp: " << e.what() << "\n";
    return e.code() == ErrorCode::UnreadableFile ? 2 : 1;
  } catch (const std::runtime_error& e) {
    std::cerr << "qgp: " << e.what() << "\n";
    return 1;
  }
  print_summary(result, command.output);
  if (command.report.empty()) return 0;
  std::ofstream out(command.report);
  out << Json{{"status", "ok"}, {"stitch", result}}.dump(2) << "\n";
  if (out) return 0;
  std::cerr << "qgp: cannot write report '" << command.report << "'\n";
  return 1;
}

}  // namespace qgp::cli

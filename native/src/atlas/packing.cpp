#include "atlas/packing.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/error.h"

namespace qgp {
namespace {

// Bottom-left packing of rectangles into a width x height texture: the skyline (the height of the
// packed area over each column range) as segments (first column, height), left to right.
class Skyline {
 public:
  Skyline(int width, int height) : width_(width), height_(height), segments_{{0, 0}} {}
  // The placement of a w x h rectangle whose top is lowest (then leftmost), or false.
  bool find(int w, int h, TexelPoint* at) const {
    bool found = false;
    int best_top = 0;
    for (size_t i = 0; i < segments_.size(); ++i) {
      const int x = segments_[i][0];
      if (x + w > width_) break;
      int y = 0;
      for (size_t j = i; j < segments_.size() && segments_[j][0] < x + w; ++j) y = std::max(y, segments_[j][1]);
      if (y + h > height_ || (found && y + h >= best_top)) continue;
      found = true;
      best_top = y + h;
      *at = {x, y};
    }
    return found;
  }
  void add(const TexelPoint& at, int w, int h) {
    std::vector<TexelPoint> next;
    const int end = at[0] + w;
    int height_at_end = 0;
    for (const TexelPoint& s : segments_)
      if (s[0] <= end) height_at_end = s[1];
    for (const TexelPoint& s : segments_)
      if (s[0] < at[0]) next.push_back(s);
    next.push_back({at[0], at[1] + h});
    if (end < width_) next.push_back({end, height_at_end});
    for (const TexelPoint& s : segments_)
      if (s[0] > end) next.push_back(s);
    segments_.clear();
    for (const TexelPoint& s : next)  // merge equal neighbours
      if (segments_.empty() || segments_.back()[1] != s[1]) segments_.push_back(s);
  }

 private:
  int width_, height_;
  std::vector<TexelPoint> segments_;
};

// Packs charts of the given sizes in cells (longest first) at k texels per quad side, each in a rectangle `gutter`
// texels wider and higher (the chart goes gutter / 2 texels in); false when one does not fit.
bool pack_charts(const std::vector<TexelPoint>& size, int width, int height, int k, int gutter,
                 std::vector<ChartPlacement>* placements) {
  std::vector<int> order(size.size());
  for (size_t c = 0; c < order.size(); ++c) order[c] = static_cast<int>(c);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return std::max(size[a][0], size[a][1]) > std::max(size[b][0], size[b][1]); });
  Skyline skyline(width, height);
  placements->assign(size.size(), ChartPlacement{});
  for (int c : order) {
    TexelPoint best{0, 0};
    int best_turns = -1;
    for (int turns = 0; turns < 2; ++turns) {
      const long long wide = static_cast<long long>(k) * size[c][turns] + gutter;
      const long long high = static_cast<long long>(k) * size[c][1 - turns] + gutter;
      if (wide > width || high > height) continue;
      const int w = static_cast<int>(wide), h = static_cast<int>(high);
      TexelPoint at;
      if (!skyline.find(w, h, &at)) continue;
      const int top = at[1] + h;
      if (best_turns >= 0 && top >= best[1] + k * size[c][1 - best_turns] + gutter) continue;
      best = at;
      best_turns = turns;
    }
    if (best_turns < 0) return false;
    skyline.add(best, k * size[c][best_turns] + gutter, k * size[c][1 - best_turns] + gutter);
    (*placements)[c] = {best, best_turns};
  }
  return true;
}

std::string size_text(int w, int h) { return std::to_string(w) + " x " + std::to_string(h); }

constexpr int kLargestTexture = 65536;  // texels per side (and per quad, and of the gutter)

void check_options_sizes(const AtlasOptions& o) {
  if (o.texture_width <= 0 || o.texture_height <= 0 || o.texels_per_quad < 0 || o.gutter < 0)
    throw Error(ErrorCode::InvalidArgument, "atlas: texture " + size_text(o.texture_width, o.texture_height) + ", " +
                                                std::to_string(o.texels_per_quad) + " texels per quad and a " +
                                                std::to_string(o.gutter) +
                                                "-texel gutter: sizes must be positive (texels per quad 0: chosen)");
  if (o.texture_width > kLargestTexture || o.texture_height > kLargestTexture || o.gutter > kLargestTexture ||
      o.texels_per_quad > kLargestTexture)
    throw Error(ErrorCode::InvalidArgument, "atlas: texture " + size_text(o.texture_width, o.texture_height) + ", " +
                                                std::to_string(o.texels_per_quad) + " texels per quad, gutter " +
                                                std::to_string(o.gutter) + ": sizes up to " +
                                                std::to_string(kLargestTexture) + " texels are possible");
  if (o.mip_levels < 0 || o.mip_levels > 8)
    throw Error(ErrorCode::InvalidArgument,
                "atlas: " + std::to_string(o.mip_levels) + " seam-free mip levels asked; 0 to 8 are possible");
  const int block = 1 << o.mip_levels;
  if (o.texture_width % block || o.texture_height % block)
    throw Error(ErrorCode::InvalidArgument, "atlas: a " + size_text(o.texture_width, o.texture_height) +
                                                " texture cannot keep " + std::to_string(o.mip_levels) +
                                                " mip levels seam-free: its sides must be multiples of " +
                                                std::to_string(block));
  const int k = o.texels_per_quad;
  if (o.mip_levels > 0 && k > 0 && (k < block || (k & (k - 1))))
    throw Error(ErrorCode::InvalidArgument,
                "atlas: " + std::to_string(k) + " texels per quad cannot keep " + std::to_string(o.mip_levels) +
                    " mip levels seam-free: it must be a power of two of at least " + std::to_string(block));
}

// The gutter used: for mip levels, the one asked raised to a multiple of 2^(L+1) (at least one texel per chart side
// at level L).
int gutter_used(const AtlasOptions& o) {
  if (o.mip_levels == 0) return o.gutter;
  const int step = 2 << o.mip_levels;
  return std::max(step, (o.gutter + step - 1) / step * step);
}

// The texels per quad side tried at step s = 1, 2, ...: every whole number, or for mip levels the powers of two
// from 2^L on.
int texels_at_step(int step, int mip_levels) { return mip_levels == 0 ? step : (1 << mip_levels) << (step - 1); }

// The largest K for which the charts pack (a binary search over the steps; smaller squares pack at least as well),
// or the smallest K when none does.
int largest_packing_texels(const AtlasOptions& o, int largest, const std::function<bool(int)>& fits) {
  int hi = o.mip_levels == 0 ? largest : 1;
  while (o.mip_levels > 0 && texels_at_step(hi + 1, o.mip_levels) <= largest && hi < 16) ++hi;
  int lo = 0;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (fits(texels_at_step(mid, o.mip_levels)))
      lo = mid;
    else
      hi = mid - 1;
  }
  return texels_at_step(std::max(lo, 1), o.mip_levels);
}

}  // namespace

void check_atlas_options(const AtlasOptions& options) { check_options_sizes(options); }

AtlasPacking pack_atlas(const std::vector<TexelPoint>& chart_size, double cells, const AtlasOptions& options,
                        const std::string& what) {
  const int W = options.texture_width, H = options.texture_height;
  AtlasPacking packing;
  packing.gutter = gutter_used(options);
  const int largest = std::max(1, static_cast<int>(std::sqrt(double(W) * H / std::max(cells, 1.0))));
  auto fits = [&](int k) { return pack_charts(chart_size, W, H, k, packing.gutter, &packing.placements); };
  const int k = options.texels_per_quad > 0 ? options.texels_per_quad : largest_packing_texels(options, largest, fits);
  if (!fits(k))
    throw Error(ErrorCode::InvalidArgument, "atlas: " + what + " do not fit a " + size_text(W, H) + " texture at " +
                                                std::to_string(k) +
                                                " texel(s) per quad with the gutter; ask for a larger texture or "
                                                "fewer quads");
  packing.texels_per_quad = k;
  return packing;
}

void to_json(Json& j, const AtlasFigures& a) {
  j = Json{{"charts", a.num_charts},
           {"texels_per_quad", a.texels_per_quad},
           {"texture_width", a.texture_width},
           {"texture_height", a.texture_height},
           {"seam_edges", a.seam_edges},
           {"texture_use", a.texture_use},
           {"gutter", a.gutter},
           {"mip_levels", a.mip_levels}};
}

}  // namespace qgp

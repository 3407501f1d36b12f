#include "common/render/tile_selection.h"

#include "common/model/scene.h"

#include <charconv>

namespace ls {
namespace {

// "A<sep>B" with A and B decimal integers (no sign, no spaces, no leading zero: "01/3" would name
// shard 1's partial file apart from "1/3"'s); false when the text is anything else.
bool parse_pair(const std::string& text, char sep, uint64_t& a, uint64_t& b) {
  const size_t at = text.find(sep);
  if (at == std::string::npos || at == 0 || at + 1 == text.size()) return false;
  if ((text[0] == '0' && at > 1) || (text[at + 1] == '0' && at + 2 < text.size())) return false;
  const char* first = text.data();
  const char* mid = first + at;
  const char* last = first + text.size();
  const auto ra = std::from_chars(first, mid, a);
  const auto rb = std::from_chars(mid + 1, last, b);
  return ra.ec == std::errc() && ra.ptr == mid && rb.ec == std::errc() && rb.ptr == last;
}

bool parse_number(const std::string& text, uint64_t& v) {
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  return !text.empty() && r.ec == std::errc() && r.ptr == text.data() + text.size();
}

}  // namespace

std::string TileGrid::describe() const {
  return std::to_string(count()) + " tile" + (count() == 1 ? "" : "s") + " (" + std::to_string(columns()) + " x " +
         std::to_string(rows()) + " of " + std::to_string(tile_size) + " px)";
}

TileSet all_tiles(const TileGrid& grid) {
  TileSet t(grid.count());
  for (uint32_t i = 0; i < t.size(); ++i) t[i] = i;
  return t;
}

TileSet parse_tile_range(const std::string& text, const TileGrid& grid) {
  uint64_t a = 0, b = 0;
  const std::string flag = "--tiles " + text;
  if (!parse_pair(text, ':', a, b))
    throw InputError(flag + ": expected A:B, the tiles A to B-1, in decimal without leading zeros (e.g. 0:16)");
  if (a >= b) throw InputError(flag + ": A must be less than B (the range A:B holds the tiles A to B-1)");
  if (b > grid.count())
    throw InputError(flag + ": past the last tile; the image has " + grid.describe() + ", so B <= " +
                     std::to_string(grid.count()));
  TileSet t;
  for (uint64_t i = a; i < b; ++i) t.push_back(uint32_t(i));
  return t;
}

TileSet parse_shard(const std::string& text, const TileGrid& grid) {
  uint64_t k = 0, n = 0;
  const std::string flag = "--shard " + text;
  if (!parse_pair(text, '/', k, n))
    throw InputError(flag + ": expected K/N, shard K of N counted from 0, in decimal without leading zeros (e.g. 0/8)");
  if (n == 0) throw InputError(flag + ": N must be at least 1");
  if (k >= n) throw InputError(flag + ": K must be less than N (shards are numbered 0 to N-1)");
  if (k >= grid.count())
    throw InputError(flag + ": this shard would have no tile; the image has " + grid.describe() +
                     ": use at most that many shards or a smaller --tile-size");
  TileSet t;
  for (uint64_t i = k; i < grid.count(); i += n) t.push_back(uint32_t(i));
  return t;
}

std::vector<uint32_t> tile_pixels(const TileGrid& grid, const TileSet& tiles) {
  std::vector<char> chosen(grid.count(), 0);
  for (uint32_t t : tiles) chosen.at(t) = 1;
  std::vector<uint32_t> pixels;
  for (uint32_t y = 0; y < grid.height; ++y)
    for (uint32_t x = 0; x < grid.width; ++x)
      if (chosen[grid.tile_of(x, y)]) pixels.push_back(y * grid.width + x);
  return pixels;
}

std::string tile_ranges_text(const TileSet& tiles) {
  std::string s;
  for (size_t i = 0; i < tiles.size();) {
    size_t j = i;
    while (j + 1 < tiles.size() && tiles[j + 1] == tiles[j] + 1) ++j;
    if (!s.empty()) s += ",";
    s += std::to_string(tiles[i]);
    if (j > i) {
      s += '-';
      s += std::to_string(tiles[j]);
    }
    i = j + 1;
  }
  return s;
}

TileSet parse_tile_ranges_text(const std::string& text, uint32_t tile_count) {
  TileSet t;
  size_t start = 0;
  while (start < text.size()) {
    size_t comma = text.find(',', start);
    if (comma == std::string::npos) comma = text.size();
    const std::string item = text.substr(start, comma - start);
    uint64_t a = 0, b = 0;
    if (parse_pair(item, '-', a, b)) {
      if (a >= b) throw InputError("tile list '" + text + "': bad range '" + item + "'");
    } else if (parse_number(item, a)) {
      b = a;
    } else {
      throw InputError("tile list '" + text + "': '" + item + "' is not a tile or a range A-B");
    }
    if (b >= tile_count)
      throw InputError("tile list '" + text + "': tile " + std::to_string(b) + " is past the last tile (" +
                       std::to_string(tile_count) + " tiles)");
    for (uint64_t i = a; i <= b; ++i) {
      if (!t.empty() && i <= t.back()) throw InputError("tile list '" + text + "' is not ascending");
      t.push_back(uint32_t(i));
    }
    start = comma + 1;
    if (comma + 1 == text.size()) throw InputError("tile list '" + text + "' ends with a comma");
  }
  return t;
}

}  // namespace ls

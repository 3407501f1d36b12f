// Which pixels a sharded render computes (docs/usage.md, "Sharded renders").  The image is cut into square
// tiles of `tile_size` pixels, numbered row-major from the top-left corner; the tiles of the last
// column and row are cut off by the image border.  A shard renders a set of whole tiles.
//
// Tiles, not sample ranges: a pixel's value is a float sum of its samples' contributions in a fixed
// order, and float addition is not associative, so sums over sample ranges cannot be merged into the
// single run's value bit for bit.  With tiles every pixel is accumulated whole in one shard, exactly
// as the single run accumulates it, so merging is copying.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ls {

struct TileGrid {
  uint32_t width = 0, height = 0, tile_size = 32;
  uint32_t columns() const { return (width + tile_size - 1) / tile_size; }
  uint32_t rows() const { return (height + tile_size - 1) / tile_size; }
  uint32_t count() const { return columns() * rows(); }
  uint32_t tile_of(uint32_t x, uint32_t y) const { return (y / tile_size) * columns() + x / tile_size; }
  std::string describe() const;  // "6 tiles (3 x 2 of 32 px)"
};

// Tile indices, ascending, each once.
using TileSet = std::vector<uint32_t>;

TileSet all_tiles(const TileGrid& grid);

// `--tiles A:B`: the tiles A, A+1, ..., B-1 (half-open, like a slice).  Throws InputError naming the
// flag and the grid when A >= B, B > the number of tiles, or the text is not two integers.
TileSet parse_tile_range(const std::string& text, const TileGrid& grid);

// `--shard K/N`: the tiles t with t mod N == K, spread over the whole image so that shards take
// about equal time.  Throws InputError when N == 0, K >= N, the shard would have no tile, or the text
// is not two integers.
TileSet parse_shard(const std::string& text, const TileGrid& grid);

// The pixels of the tiles as row-major indices, ascending (the order the full render visits them).
std::vector<uint32_t> tile_pixels(const TileGrid& grid, const TileSet& tiles);

// "0-3,8,10-12" and back (the partial's header; parse throws InputError on anything malformed,
// unsorted, repeated or not below tile_count).
std::string tile_ranges_text(const TileSet& tiles);
TileSet parse_tile_ranges_text(const std::string& text, uint32_t tile_count);

}  // namespace ls

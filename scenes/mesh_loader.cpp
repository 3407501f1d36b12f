// One OBJ/PLY/OFF/STL mesh -> a one-object scene.
//
// The readers are this file's own: strict, bounds-checked, and faithful to the file.  OpenMesh 9's
// readers (the first choice) corrupt the heap on malformed OBJ faces, crash on malformed PLY headers
// and loop forever on others, and silently drop faces that are not manifold, which would shift
// triangle ids.  Here every polygon of the file is kept and fan-triangulated in file order (triangle
// id = that order, docs/design.md §9); anything malformed is an InputError naming the file and line.
//
// Normals: the file's where it has them (OBJ vn, OFF NOFF, PLY nx ny nz), made unit; elsewhere
// area-weighted averages of the faces around each vertex.
#include "scenes/load_scene.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>
#include <unordered_map>

namespace ls {

namespace {

// What a reader produces: positions, optional normals (zero = none), triangles.
struct Polygons {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // empty, or one per position
  std::vector<glm::uvec3> triangles;

  void add_fan(const std::vector<uint32_t>& corners) {
    for (size_t i = 1; i + 1 < corners.size(); ++i) triangles.emplace_back(corners[0], corners[i], corners[i + 1]);
  }
};

class Failer {
 public:
  explicit Failer(const std::string& path) : path_(path) {}
  [[noreturn]] void operator()(const std::string& what) const { throw InputError(path_ + ": " + what); }
  [[noreturn]] void operator()(size_t line, const std::string& what) const {
    throw InputError(path_ + ": line " + std::to_string(line) + ": " + what);
  }

 private:
  const std::string& path_;
};

// ---- text ----

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Lines of a text, '\r' removed, counted from 1.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    line = text_.substr(pos_, end - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end + 1;
    ++number_;
    return true;
  }
  size_t number() const { return number_; }
  size_t remaining() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  std::string_view text_;
  size_t pos_ = 0, number_ = 0;
};

// Whitespace-separated tokens of a line, up to a comment character (0: none).
std::vector<std::string_view> split(std::string_view line, char comment = 0) {
  if (comment) line = line.substr(0, line.find(comment));
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const size_t b = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > b) tokens.push_back(line.substr(b, i - b));
  }
  return tokens;
}

// A whole token as a finite float (locale-independent; "nan", "inf" and overflow refused).
bool parse_float(std::string_view t, float& out) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  double d = 0.0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), d);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size() || !std::isfinite(d) ||
      std::fabs(d) > double(std::numeric_limits<float>::max()))
    return false;
  out = float(d);
  return true;
}

bool parse_int(std::string_view t, long long& out) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  return !t.empty() && ec == std::errc() && ptr == t.data() + t.size();
}

// ---- OBJ ----

// OBJ normals belong to face corners: a vertex is a (position, normal) pair, so one position used
// with two normals becomes two vertices.  Statements other than v, vt, vn and f are ignored.
Polygons read_obj(std::string_view text, const Failer& fail) {
  Polygons out;
  std::vector<glm::vec3> v, vn;
  size_t vt = 0;
  std::vector<uint32_t> plain;                       // position -> vertex, for corners without a normal
  std::unordered_map<uint64_t, uint32_t> with_normal;  // (position, normal) -> vertex
  std::vector<uint32_t> corners;
  Lines lines(text);
  std::string_view line;
  while (lines.next(line)) {
    const std::vector<std::string_view> tok = split(line, '#');
    if (tok.empty()) continue;
    const size_t n = lines.number();
    if (tok[0] == "v" || tok[0] == "vn") {
      glm::vec3 p;
      if (tok.size() < 4 || !parse_float(tok[1], p.x) || !parse_float(tok[2], p.y) || !parse_float(tok[3], p.z))
        fail(n, std::string(tok[0]) + " needs three finite numbers");
      (tok[0] == "v" ? v : vn).push_back(p);
    } else if (tok[0] == "vt") {
      ++vt;
    } else if (tok[0] == "f") {
      if (tok.size() < 4) fail(n, "a face needs at least three corners");
      corners.clear();
      for (size_t c = 1; c < tok.size(); ++c) {
        // v, v/t, v//n or v/t/n; negative indices count back from the last element defined so far.
        const std::string_view corner = tok[c];
        std::string_view part[3];
        size_t parts = 0, start = 0;
        for (;;) {
          const size_t slash = corner.find('/', start);
          if (parts == 3) fail(n, "bad face corner '" + std::string(corner) + "'");
          part[parts++] = corner.substr(start, slash == std::string_view::npos ? slash : slash - start);
          if (slash == std::string_view::npos) break;
          start = slash + 1;
        }
        const size_t count[3] = {v.size(), vt, vn.size()};
        long long idx[3] = {-1, -1, -1};
        for (size_t k = 0; k < parts; ++k) {
          if (part[k].empty() && k == 1 && parts == 3) continue;  // the missing t of v//n
          long long i = 0;
          if (!parse_int(part[k], i)) fail(n, "bad face corner '" + std::string(corner) + "'");
          if (i == 0 || (i > 0 && size_t(i) > count[k]) || (i < 0 && size_t(-i) > count[k]))
            fail(n, "face corner '" + std::string(corner) + "' refers to a missing element");
          idx[k] = i > 0 ? i - 1 : static_cast<long long>(count[k]) + i;
        }
        uint32_t vertex;
        const size_t next = out.positions.size();
        if (next >= UINT32_MAX) fail(n, "more than 2^32 vertices");
        if (idx[2] < 0) {
          if (plain.size() < v.size()) plain.resize(v.size(), UINT32_MAX);
          uint32_t& slot = plain[size_t(idx[0])];
          if (slot == UINT32_MAX) {
            slot = uint32_t(next);
            out.positions.push_back(v[size_t(idx[0])]);
            out.normals.emplace_back(0.0f);  // computed later
          }
          vertex = slot;
        } else {
          const auto [it, fresh] = with_normal.try_emplace(uint64_t(idx[0]) << 32 | uint64_t(idx[2]), uint32_t(next));
          if (fresh) {
            out.positions.push_back(v[size_t(idx[0])]);
            out.normals.push_back(vn[size_t(idx[2])]);
          }
          vertex = it->second;
        }
        corners.push_back(vertex);
      }
      out.add_fan(corners);
    }
  }
  return out;
}

// ---- OFF ----

Polygons read_off(std::string_view text, const Failer& fail) {
  Polygons out;
  Lines lines(text);
  std::string_view line;
  std::vector<std::string_view> tok;
  // The next line with content, comments removed.
  const auto next = [&](const char* what) {
    while (lines.next(line)) {
      tok = split(line, '#');
      if (!tok.empty()) return;
    }
    fail("file ends before " + std::string(what));
  };
  next("the header");
  // [ST][C][N]OFF; 4OFF, nOFF and BINARY are not supported.
  std::string_view header = tok[0];
  if (header.size() < 3 || header.substr(header.size() - 3) != "OFF") fail(1, "not an OFF file (no OFF header)");
  std::string_view prefix = header.substr(0, header.size() - 3);
  if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
  if (!prefix.empty() && prefix[0] == 'C') prefix.remove_prefix(1);
  const bool has_normals = !prefix.empty() && prefix[0] == 'N';
  if (has_normals) prefix.remove_prefix(1);
  if (!prefix.empty()) fail(lines.number(), "unsupported OFF variant '" + std::string(header) + "'");
  tok.erase(tok.begin());
  if (!tok.empty() && tok[0] == "BINARY") fail(lines.number(), "binary OFF is not supported");
  if (tok.empty()) next("the vertex and face counts");
  long long nv = 0, nf = 0;
  if (tok.size() < 2 || !parse_int(tok[0], nv) || !parse_int(tok[1], nf) || nv < 0 || nf < 0)
    fail(lines.number(), "expected the vertex and face counts");
  if (size_t(nv) >= UINT32_MAX) fail(lines.number(), "more than 2^32 vertices");

  const size_t guess = lines.remaining() / 6;  // no huge reservation on the word of a bad count
  out.positions.reserve(std::min(size_t(nv), guess));
  if (has_normals) out.normals.reserve(std::min(size_t(nv), guess));
  for (long long i = 0; i < nv; ++i) {
    next("all vertices are read");
    glm::vec3 p, nrm;
    if (tok.size() < 3 || !parse_float(tok[0], p.x) || !parse_float(tok[1], p.y) || !parse_float(tok[2], p.z))
      fail(lines.number(), "a vertex needs three finite numbers");
    out.positions.push_back(p);
    if (has_normals) {
      if (tok.size() < 6 || !parse_float(tok[3], nrm.x) || !parse_float(tok[4], nrm.y) || !parse_float(tok[5], nrm.z))
        fail(lines.number(), "an NOFF vertex needs three finite normal components");
      out.normals.push_back(nrm);
    }
  }
  std::vector<uint32_t> corners;
  for (long long f = 0; f < nf; ++f) {
    next("all faces are read");
    long long k = 0;
    if (!parse_int(tok[0], k) || k < 3 || size_t(k) >= tok.size())
      fail(lines.number(), "a face needs a corner count of at least 3 and that many indices");
    corners.clear();
    for (long long c = 1; c <= k; ++c) {
      long long idx = 0;
      if (!parse_int(tok[size_t(c)], idx) || idx < 0 || idx >= nv)
        fail(lines.number(), "bad face index '" + std::string(tok[size_t(c)].substr(0, 40)) + "'");
      corners.push_back(uint32_t(idx));
    }
    out.add_fan(corners);  // anything after the indices (a colour) is ignored
  }
  return out;
}

// ---- STL ----

// STL stores each facet's corners separately; equal positions are welded into one vertex (so that
// normals are shared), keeping every facet.
class Welder {
 public:
  explicit Welder(Polygons& out) : out_(out) {}
  uint32_t operator()(const glm::vec3& p) {
    Key k;
    std::memcpy(k.data(), &p, 12);  // bitwise: -0 and 0 stay apart, NaN can be looked up
    const auto [it, fresh] = index_.try_emplace(k, uint32_t(out_.positions.size()));
    if (fresh) out_.positions.push_back(p);
    return it->second;
  }

 private:
  using Key = std::array<uint32_t, 3>;
  struct Hash {
    size_t operator()(const Key& k) const {
      uint64_t h = k[0] * 0x9e3779b97f4a7c15ULL;
      h = (h ^ k[1]) * 0xbf58476d1ce4e5b9ULL;
      h = (h ^ k[2]) * 0x94d049bb133111ebULL;
      return size_t(h ^ (h >> 31));
    }
  };
  Polygons& out_;
  std::unordered_map<Key, uint32_t, Hash> index_;
};

Polygons read_stl(std::string_view data, const Failer& fail) {
  Polygons out;
  Welder weld(out);
  std::vector<uint32_t> corners;
  // Binary: an 80-byte header, a facet count, and exactly 50 bytes per facet.
  if (data.size() >= 84) {
    uint32_t count;
    std::memcpy(&count, data.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) count = __builtin_bswap32(count);
    if (84 + 50 * uint64_t(count) == data.size()) {
      for (uint32_t f = 0; f < count; ++f) {
        corners.clear();
        for (int c = 0; c < 3; ++c) {
          float xyz[3];
          std::memcpy(xyz, data.data() + 84 + 50 * size_t(f) + 12 + 12 * c, 12);
          if constexpr (std::endian::native == std::endian::big)
            for (float& x : xyz) x = std::bit_cast<float>(__builtin_bswap32(std::bit_cast<uint32_t>(x)));
          corners.push_back(weld(glm::vec3(xyz[0], xyz[1], xyz[2])));
        }
        out.add_fan(corners);
      }
      return out;
    }
  }
  // ASCII: solid NAME (facet normal N N N outer loop (vertex X Y Z)+ endloop endfacet)* endsolid
  Lines lines(data);
  std::string_view line;
  std::vector<std::string_view> tok;
  size_t t = 0;
  const auto token = [&]() -> std::string_view {
    while (t >= tok.size()) {
      if (!lines.next(line)) return {};
      tok = split(line);
      t = 0;
    }
    return tok[t++];
  };
  const auto expect = [&](std::string_view word) {
    const std::string_view got = token();
    if (got != word)
      fail(lines.number(), "expected '" + std::string(word) + "', found '" + std::string(got.substr(0, 40)) + "'");
  };
  if (token() != "solid") fail("not an STL file (no 'solid' and the size does not match a binary facet count)");
  t = tok.size();  // the rest of the first line is the solid's name
  std::string_view word = token();
  while (word == "facet") {
    expect("normal");
    for (int k = 0; k < 3; ++k) token();  // facet normals are not used (some writers put nan here)
    expect("outer");
    expect("loop");
    corners.clear();
    while ((word = token()) == "vertex") {
      glm::vec3 p;
      if (!parse_float(token(), p.x) || !parse_float(token(), p.y) || !parse_float(token(), p.z))
        fail(lines.number(), "a vertex needs three finite numbers");
      if (out.positions.size() >= UINT32_MAX) fail(lines.number(), "more than 2^32 vertices");
      corners.push_back(weld(p));
    }
    if (word != "endloop") fail(lines.number(), "expected 'vertex' or 'endloop'");
    if (corners.size() < 3) fail(lines.number(), "a facet needs at least three vertices");
    expect("endfacet");
    out.add_fan(corners);
    word = token();
  }
  if (!word.empty() && word != "endsolid") fail(lines.number(), "expected 'facet' or 'endsolid'");
  return out;
}

// ---- PLY ----

enum class PlyType { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

bool ply_type(std::string_view s, PlyType& t) {
  static const std::pair<std::string_view, PlyType> names[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},      {"uchar", PlyType::Uint8},   {"uint8", PlyType::Uint8},
      {"short", PlyType::Int16},   {"int16", PlyType::Int16},    {"ushort", PlyType::Uint16}, {"uint16", PlyType::Uint16},
      {"int", PlyType::Int32},     {"int32", PlyType::Int32},    {"uint", PlyType::Uint32},   {"uint32", PlyType::Uint32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64}, {"float64", PlyType::Float64}};
  for (const auto& [name, type] : names)
    if (s == name) {
      t = type;
      return true;
    }
  return false;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::Int8: case PlyType::Uint8: return 1;
    case PlyType::Int16: case PlyType::Uint16: return 2;
    case PlyType::Int32: case PlyType::Uint32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 0;
}

struct PlyProperty {
  std::string name;
  bool list = false;
  PlyType count_type = PlyType::Uint8, type = PlyType::Float32;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

// Values of the body, one at a time, from text tokens or from bytes of either order.
class PlyBody {
 public:
  PlyBody(std::string_view body, int format, const Failer& fail) : body_(body), format_(format), fail_(fail) {}

  // `at` (element name, index) is what the messages name.
  double read(PlyType t, const std::pair<const std::string*, uint64_t>& at) {
    const auto what = [&] { return *at.first + " " + std::to_string(at.second); };
    if (format_ == 0) {
      while (pos_ < body_.size() && is_space(body_[pos_])) ++pos_;
      const size_t b = pos_;
      while (pos_ < body_.size() && !is_space(body_[pos_])) ++pos_;
      const std::string_view tok = body_.substr(b, pos_ - b);
      if (tok.empty()) fail_("file ends inside " + what());
      if (t == PlyType::Float32 || t == PlyType::Float64) {
        float f;
        if (!parse_float(tok, f)) fail_(what() + ": '" + std::string(tok.substr(0, 40)) + "' is not a finite number");
        return f;
      }
      long long i;
      if (!parse_int(tok, i)) fail_(what() + ": '" + std::string(tok.substr(0, 40)) + "' is not an integer");
      return double(i);
    }
    const size_t n = ply_size(t);
    if (body_.size() - pos_ < n) fail_("file ends inside " + what());
    unsigned char b[8];
    std::memcpy(b, body_.data() + pos_, n);
    pos_ += n;
    const bool big = format_ == 2;
    if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (t) {
      case PlyType::Int8: return double(int8_t(b[0]));
      case PlyType::Uint8: return double(b[0]);
      case PlyType::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::Uint16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Uint32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Float32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0.0;
  }
  size_t remaining() const { return body_.size() - pos_; }

 private:
  std::string_view body_;
  size_t pos_ = 0;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  const Failer& fail_;
};

Polygons read_ply(std::string_view data, const Failer& fail) {
  Lines lines(data);
  std::string_view line;
  std::vector<PlyElement> elements;
  int format = -1;
  if (!lines.next(line) || split(line) != std::vector<std::string_view>{"ply"}) fail(1, "not a PLY file (no 'ply' line)");
  for (;;) {
    if (!lines.next(line)) fail("file ends inside the header");
    const std::vector<std::string_view> tok = split(line);
    const size_t n = lines.number();
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "end_header") break;
    if (tok[0] == "format") {
      if (tok.size() != 3) fail(n, "bad format line");
      format = tok[1] == "ascii" ? 0 : tok[1] == "binary_little_endian" ? 1 : tok[1] == "binary_big_endian" ? 2 : -1;
      if (format < 0) fail(n, "unknown PLY format '" + std::string(tok[1].substr(0, 40)) + "'");
    } else if (tok[0] == "element") {
      long long count = 0;
      if (tok.size() != 3 || !parse_int(tok[2], count) || count < 0) fail(n, "bad element line");
      elements.push_back({std::string(tok[1]), uint64_t(count), {}});
    } else if (tok[0] == "property") {
      if (elements.empty()) fail(n, "property before any element");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list" && ply_type(tok[2], p.count_type) && ply_type(tok[3], p.type)) {
        p.list = true;
        p.name = tok[4];
      } else if (tok.size() == 3 && ply_type(tok[1], p.type)) {
        p.name = tok[2];
      } else {
        fail(n, "bad property line");
      }
      elements.back().properties.push_back(p);
    } else {
      fail(n, "unknown header line '" + std::string(tok[0].substr(0, 40)) + "'");
    }
  }
  if (format < 0) fail("no format line in the header");
  const size_t header_end = data.size() - lines.remaining();

  const PlyElement* vertex = nullptr;
  for (const PlyElement& e : elements)
    if (e.name == "vertex") vertex = &e;
  if (!vertex) fail("no vertex element");
  const auto find = [](const PlyElement& e, const char* name, bool list) {
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].name == name && e.properties[i].list == list) return int(i);
    return -1;
  };
  const int px = find(*vertex, "x", false), py = find(*vertex, "y", false), pz = find(*vertex, "z", false);
  if (px < 0 || py < 0 || pz < 0) fail("the vertex element lacks x, y or z");
  const int nx = find(*vertex, "nx", false), ny = find(*vertex, "ny", false), nz = find(*vertex, "nz", false);
  const bool has_normals = nx >= 0 && ny >= 0 && nz >= 0;
  if (vertex->count >= UINT32_MAX) fail("more than 2^32 vertices");

  Polygons out;
  PlyBody body(data.substr(header_end), format, fail);
  std::vector<double> values;
  std::vector<uint32_t> corners;
  for (const PlyElement& e : elements) {
    if (e.properties.empty()) continue;  // takes no room however large its count
    const bool is_vertex = &e == vertex;
    const int pf = e.name == "face" ? std::max(find(e, "vertex_indices", true), find(e, "vertex_index", true)) : -1;
    if (is_vertex) {
      const size_t guess = std::min<uint64_t>(e.count, body.remaining() / 3);  // no huge reservation on a bad count
      out.positions.reserve(guess);
      if (has_normals) out.normals.reserve(guess);
    }
    values.resize(e.properties.size());
    for (uint64_t i = 0; i < e.count; ++i) {
      const std::pair<const std::string*, uint64_t> at(&e.name, i);
      const auto what = [&] { return e.name + " " + std::to_string(i); };
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.list) {
          values[k] = body.read(p.type, at);
          continue;
        }
        const double count = body.read(p.count_type, at);
        if (!(count >= 0.0) || count != std::floor(count)) fail(what() + ": bad list length");
        if (int(k) == pf) {
          if (count < 3) fail(what() + ": a face needs at least three vertices");
          corners.clear();
          for (double c = 0; c < count; ++c) {
            const double idx = body.read(p.type, at);
            if (!(idx >= 0.0) || idx != std::floor(idx) || idx >= double(vertex->count))
              fail(what() + ": vertex index out of range");
            corners.push_back(uint32_t(idx));
          }
          out.add_fan(corners);
        } else {
          for (double c = 0; c < count; ++c) body.read(p.type, at);
        }
      }
      if (is_vertex) {
        const glm::vec3 pos{float(values[size_t(px)]), float(values[size_t(py)]), float(values[size_t(pz)])};
        if (!std::isfinite(pos.x) || !std::isfinite(pos.y) || !std::isfinite(pos.z))
          fail(what() + ": coordinate is not a finite number");
        out.positions.push_back(pos);
        if (has_normals)
          out.normals.emplace_back(float(values[size_t(nx)]), float(values[size_t(ny)]), float(values[size_t(nz)]));
      }
    }
  }
  return out;
}

// ---- common ----

// Unit normals: the file's where usable, else area-weighted face normals (the cross product's length
// is twice the area); a vertex on no face gets +z.
void finish_normals(Polygons& m) {
  std::vector<glm::vec3> computed;
  if (m.normals.size() != m.positions.size()) m.normals.assign(m.positions.size(), glm::vec3(0.0f));
  for (glm::vec3& n : m.normals) {
    const float len = glm::length(n);
    if (len > 0.0f && std::isfinite(len)) {
      n /= len;
      continue;
    }
    if (computed.empty()) {
      computed.assign(m.positions.size(), glm::vec3(0.0f));
      for (const glm::uvec3& t : m.triangles) {
        const glm::vec3 c = glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
        computed[t.x] += c;
        computed[t.y] += c;
        computed[t.z] += c;
      }
    }
    const glm::vec3 c = computed[size_t(&n - m.normals.data())];
    const float clen = glm::length(c);
    n = clen > 0.0f && std::isfinite(clen) ? c / clen : glm::vec3(0.0f, 0.0f, 1.0f);
  }
}

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

}  // namespace

Scene load_mesh_file(const std::string& path) {
  const Failer fail(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot be opened");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  Scene scene = load_mesh_bytes(std::move(buffer).str(), lower_ext(path), path);
  scene.meshes[0].name = scene.instances[0].name = std::filesystem::path(path).stem().string();
  return scene;
}

Scene load_mesh_bytes(const std::string& data, const std::string& format, const std::string& name) {
  const Failer fail(name);
  std::string ext = format;
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));

  Polygons poly;
  if (ext == ".obj") poly = read_obj(data, fail);
  else if (ext == ".off") poly = read_off(data, fail);
  else if (ext == ".stl") poly = read_stl(data, fail);
  else if (ext == ".ply") poly = read_ply(data, fail);
  else fail("unknown mesh format '" + ext + "' (expected .obj .ply .off .stl)");
  if (poly.triangles.empty()) fail("no faces");
  finish_normals(poly);

  Mesh mesh;
  mesh.name = name;
  mesh.positions = std::move(poly.positions);
  mesh.normals = std::move(poly.normals);
  mesh.triangles = std::move(poly.triangles);
  mesh.materials.assign(mesh.triangles.size(), 0);

  Scene scene;
  scene.name = name;
  scene.meshes.push_back(std::move(mesh));
  Instance inst;
  inst.name = scene.meshes[0].name;
  scene.instances.push_back(inst);
  Material grey;
  grey.albedo = glm::vec3(0.8f);
  grey.name = "default";
  scene.materials.push_back(grey);
  scene.background = glm::vec3(1.0f);  // a white sky lights a bare mesh from every direction
  validate_scene(scene);
  scene.camera = framing_camera(scene);
  return scene;
}

}  // namespace ls

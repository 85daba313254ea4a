#include "io/mesh_files.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>

#include "sdfcontour/types.h"

namespace sdfcontour::detail {

namespace {

[[noreturn]] void fail(const std::string& name, const char* kind, const std::string& reason) {
  throw Error("cannot parse '" + name + "' as " + kind + ": " + reason);
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

// Whitespace-separated tokens over bytes, with line awareness for OFF and OBJ.
class Tokens {
 public:
  explicit Tokens(std::string_view bytes) : s_(bytes) {}
  // The next token on the current line, or empty at the end of the line (not consumed).
  std::string_view on_line() {
    while (at_ < s_.size() && is_space(s_[at_]) && s_[at_] != '\n') ++at_;
    std::size_t end = at_;
    while (end < s_.size() && !is_space(s_[end])) ++end;
    const std::string_view t = s_.substr(at_, end - at_);
    at_ = end;
    return t;
  }
  // The next token anywhere, or empty at the end of the bytes.
  std::string_view next() {
    while (at_ < s_.size() && is_space(s_[at_])) ++at_;
    return on_line();
  }
  void skip_line() {
    while (at_ < s_.size() && s_[at_] != '\n') ++at_;
    if (at_ < s_.size()) ++at_;
  }
  bool done() const { return at_ >= s_.size(); }
  std::size_t remaining() const { return s_.size() - at_; }
  std::size_t position() const { return at_; }

 private:
  std::string_view s_;
  std::size_t at_ = 0;
};

std::optional<double> to_double(std::string_view t) {
  double x = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), x);
  if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

std::optional<long> to_long(std::string_view t) {
  long x = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), x);
  if (r.ec != std::errc() || r.ptr != t.data() + t.size()) return std::nullopt;
  return x;
}

// ---------------------------------------------------------------------------------------------
// PLY

enum class Scalar { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

std::optional<Scalar> scalar_type(std::string_view t) {
  if (t == "char" || t == "int8") return Scalar::Int8;
  if (t == "uchar" || t == "uint8") return Scalar::Uint8;
  if (t == "short" || t == "int16") return Scalar::Int16;
  if (t == "ushort" || t == "uint16") return Scalar::Uint16;
  if (t == "int" || t == "int32") return Scalar::Int32;
  if (t == "uint" || t == "uint32") return Scalar::Uint32;
  if (t == "float" || t == "float32") return Scalar::Float32;
  if (t == "double" || t == "float64") return Scalar::Float64;
  return std::nullopt;
}

std::size_t size_of(Scalar s) {
  switch (s) {
    case Scalar::Int8:
    case Scalar::Uint8:
      return 1;
    case Scalar::Int16:
    case Scalar::Uint16:
      return 2;
    case Scalar::Int32:
    case Scalar::Uint32:
    case Scalar::Float32:
      return 4;
    case Scalar::Float64:
      return 8;
  }
  return 8;
}

struct Property {
  std::string name;
  Scalar type = Scalar::Float64;
  bool list = false;
  Scalar count_type = Scalar::Uint8;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
};

// Reads scalars from a binary body or ASCII tokens, with bounds checks.
class PlyBody {
 public:
  PlyBody(std::string_view body, int format, const std::string& name)
      : body_(body), tokens_(body), format_(format), name_(name) {}
  double read(Scalar type) {
    if (format_ == 0) {
      const std::string_view t = tokens_.next();
      if (t.empty()) fail(name_, "a PLY file", "it ends before its elements do");
      std::optional<double> x = to_double(t);
      // The declared type rules: a float property holds a float, however many digits are written.
      if (x && type == Scalar::Float32) x = double(float(*x));
      if (!x || !std::isfinite(*x))
        fail(name_, "a PLY file", "'" + std::string(t.substr(0, 40)) + "' is not a finite number");
      return *x;
    }
    const std::size_t n = size_of(type);
    if (at_ + n > body_.size()) fail(name_, "a PLY file", "it ends before its elements do");
    unsigned char b[8];
    std::memcpy(b, body_.data() + at_, n);
    at_ += n;
    if (format_ == 2) std::reverse(b, b + n);  // big endian
    double x = 0;
    switch (type) {
      case Scalar::Int8:
        x = load<std::int8_t>(b);
        break;
      case Scalar::Uint8:
        x = load<std::uint8_t>(b);
        break;
      case Scalar::Int16:
        x = load<std::int16_t>(b);
        break;
      case Scalar::Uint16:
        x = load<std::uint16_t>(b);
        break;
      case Scalar::Int32:
        x = load<std::int32_t>(b);
        break;
      case Scalar::Uint32:
        x = load<std::uint32_t>(b);
        break;
      case Scalar::Float32:
        x = load<float>(b);
        break;
      case Scalar::Float64:
        x = load<double>(b);
        break;
    }
    if (!std::isfinite(x)) fail(name_, "a PLY file", "a NaN or infinite number");
    return x;
  }
  // The value of type T in the first sizeof(T) bytes of b (already in host order).
  template <class T>
  static double load(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof v);
    return double(v);
  }
  // Bytes left: a bound on how many items can still follow (at least one byte each).
  std::size_t remaining() const { return format_ == 0 ? tokens_.remaining() : body_.size() - at_; }

 private:
  std::string_view body_;
  Tokens tokens_;
  int format_;  // 0 ascii, 1 binary little endian, 2 binary big endian
  const std::string& name_;
  std::size_t at_ = 0;
};

int ply_header(std::string_view bytes, const std::string& name, std::vector<Element>& elements,
               std::size_t& body_start) {
  const char* kind = "a PLY file";
  if (bytes.substr(0, 3) != "ply") fail(name, kind, "it does not start with 'ply'");
  int format = -1;
  std::size_t at = 0;
  bool first = true;
  for (;;) {
    const std::size_t end = bytes.find('\n', at);
    if (end == std::string_view::npos) fail(name, kind, "no end_header line");
    std::string_view line = bytes.substr(at, end - at);
    at = end + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    Tokens t(line);
    const std::string_view key = t.next();
    if (first) {
      if (key != "ply") fail(name, kind, "it does not start with 'ply'");
      first = false;
      continue;
    }
    if (key == "format") {
      if (format >= 0) fail(name, kind, "two format lines");
      const std::string_view f = t.next();
      format = f == "ascii"                  ? 0
               : f == "binary_little_endian" ? 1
               : f == "binary_big_endian"    ? 2
                                             : -1;
      if (format < 0) fail(name, kind, "unknown format '" + std::string(f) + "'");
    } else if (key == "element") {
      Element e;
      e.name = std::string(t.next());
      const std::optional<long> count = to_long(t.next());
      if (!count || *count < 0) fail(name, kind, "an element without a valid count");
      e.count = std::size_t(*count);
      for (const Element& other : elements)
        if (other.name == e.name && (e.name == "vertex" || e.name == "face"))
          fail(name, kind, "two '" + e.name + "' elements");
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) fail(name, kind, "a property before any element");
      Property p;
      const std::string_view type = t.next();
      if (type == "list") {
        const auto count_type = scalar_type(t.next()), item = scalar_type(t.next());
        if (!count_type || !item) fail(name, kind, "a list property of unknown type");
        p.list = true, p.count_type = *count_type, p.type = *item;
      } else {
        const auto s = scalar_type(type);
        if (!s) fail(name, kind, "a property of unknown type '" + std::string(type) + "'");
        p.type = *s;
      }
      p.name = std::string(t.next());
      elements.back().properties.push_back(p);
    } else if (key == "end_header") {
      break;
    } else if (key != "comment" && key != "obj_info" && !key.empty()) {
      fail(name, kind, "unknown header line '" + std::string(line.substr(0, 40)) + "'");
    }
  }
  if (format < 0) fail(name, kind, "no format line");
  body_start = at;
  return format;
}

}  // namespace

PolygonSoup parse_ply(std::string_view bytes, const std::string& name) {
  const char* kind = "a PLY file";
  std::vector<Element> elements;
  std::size_t body_start = 0;
  const int format = ply_header(bytes, name, elements, body_start);
  PlyBody body(bytes.substr(body_start), format, name);
  PolygonSoup soup;
  for (const Element& e : elements) {
    // Every item takes at least its properties' bytes (binary) or a digit and a separator each
    // (ASCII): a count beyond the bytes left is a lie.
    std::size_t min_bytes = 0;
    for (const Property& p : e.properties)
      min_bytes += format == 0 ? 2 : size_of(p.list ? p.count_type : p.type);
    if (e.count > 0 && min_bytes == 0)
      fail(name, kind, "an element '" + e.name + "' without properties");
    if (e.count > body.remaining() / std::max<std::size_t>(min_bytes, 1) + 1)
      fail(name, kind, "element '" + e.name + "' counts more items than the file holds");
    const bool vertex = e.name == "vertex", face = e.name == "face";
    int slot[6] = {-1, -1, -1, -1, -1, -1};  // x y z nx ny nz
    int indices = -1;
    const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
    for (std::size_t q = 0; q < e.properties.size(); ++q) {
      for (int a = 0; a < 6; ++a)
        if (vertex && !e.properties[q].list && e.properties[q].name == names[a]) slot[a] = int(q);
      if (face && e.properties[q].list &&
          (e.properties[q].name == "vertex_indices" || e.properties[q].name == "vertex_index"))
        indices = int(q);
    }
    if (vertex && (slot[0] < 0 || slot[1] < 0 || slot[2] < 0))
      fail(name, kind, "vertices without x, y and z");
    const bool normals = vertex && slot[3] >= 0 && slot[4] >= 0 && slot[5] >= 0;
    if (vertex) {
      soup.points.reserve(e.count);
      if (normals) soup.normals.reserve(e.count);
    }
    for (std::size_t i = 0; i < e.count; ++i) {
      double value[6] = {0, 0, 0, 0, 0, 0};
      std::vector<long> polygon;
      for (std::size_t q = 0; q < e.properties.size(); ++q) {
        const Property& p = e.properties[q];
        if (!p.list) {
          const double x = body.read(p.type);
          for (int a = 0; a < 6; ++a)
            if (slot[a] == int(q)) value[a] = x;
          continue;
        }
        const double n = body.read(p.count_type);
        if (n < 0 || n != std::floor(n) || n > double(body.remaining()))
          fail(name, kind, "a list longer than the file");
        for (std::size_t k = 0; k < std::size_t(n); ++k) {
          const double v = body.read(p.type);
          if (int(q) == indices) {
            if (v != std::floor(v) || std::abs(v) > 2e9) fail(name, kind, "a bad vertex index");
            polygon.push_back(long(v));
          }
        }
      }
      if (vertex) {
        soup.points.push_back({value[0], value[1], value[2]});
        if (normals) soup.normals.push_back({value[3], value[4], value[5]});
      }
      if (face && indices >= 0) soup.polygons.push_back(std::move(polygon));
    }
  }
  return soup;
}

// ---------------------------------------------------------------------------------------------
// OFF

PolygonSoup parse_off(std::string_view bytes, const std::string& name) {
  const char* kind = "an OFF file";
  Tokens t(bytes);
  // Skips comments and blank lines; the next token, on a fresh line.
  auto next_line_token = [&]() -> std::string_view {
    for (;;) {
      const std::string_view tok = t.next();
      if (tok.empty() || tok[0] != '#') return tok;
      t.skip_line();
    }
  };
  std::string_view tok = next_line_token();
  const bool normals =
      tok.find('N') != std::string_view::npos && tok.find("OFF") != std::string_view::npos;
  if (tok.size() >= 3 && tok.substr(tok.size() - 3) == "OFF") tok = next_line_token();
  const std::optional<long> nv = to_long(tok), nf = to_long(t.next());
  t.on_line();  // the edge count, if any
  if (!nv || !nf || *nv < 0 || *nf < 0) fail(name, kind, "no valid vertex and face counts");
  // A vertex takes at least 6 bytes ("0 0 0\n"), a face at least 2.
  if (std::size_t(*nv) > t.remaining() / 6 + 1 || std::size_t(*nf) > t.remaining() / 2 + 1)
    fail(name, kind, "it counts more vertices or faces than the file holds");
  PolygonSoup soup;
  soup.points.reserve(std::size_t(*nv));
  auto number = [&](std::string_view token) {
    const std::optional<double> x = to_double(token);
    if (!x) fail(name, kind, "'" + std::string(token.substr(0, 40)) + "' is not a finite number");
    return *x;
  };
  for (long i = 0; i < *nv; ++i) {
    t.skip_line();
    std::array<double, 3> p;
    p[0] = number(next_line_token());
    p[1] = number(t.on_line());
    p[2] = number(t.on_line());
    soup.points.push_back(p);
    if (normals) {
      std::array<double, 3> n;
      for (double& c : n) c = number(t.on_line());
      soup.normals.push_back(n);
    }
  }
  for (long f = 0; f < *nf; ++f) {
    t.skip_line();
    const std::optional<long> count = to_long(next_line_token());
    if (!count || *count < 0 || std::size_t(*count) > t.remaining())
      fail(name, kind, "a face without a valid vertex count");
    std::vector<long> polygon;
    polygon.reserve(std::size_t(*count));
    for (long k = 0; k < *count; ++k) {
      const std::optional<long> v = to_long(t.on_line());
      if (!v) fail(name, kind, "a face with a bad vertex index");
      polygon.push_back(*v);
    }
    soup.polygons.push_back(std::move(polygon));
  }
  return soup;
}

// ---------------------------------------------------------------------------------------------
// OBJ

PolygonSoup parse_obj(std::string_view bytes, const std::string& name) {
  const char* kind = "an OBJ file";
  Tokens t(bytes);
  PolygonSoup soup;
  while (!t.done()) {
    const std::string_view key = t.on_line();
    if (key == "v") {
      std::array<double, 3> p;
      for (double& c : p) {
        const std::string_view tok = t.on_line();
        const std::optional<double> x = to_double(tok);
        if (!x)
          fail(name, kind,
               "a vertex with a bad coordinate '" + std::string(tok.substr(0, 40)) + "'");
        c = *x;
      }
      soup.points.push_back(p);
    } else if (key == "f") {
      std::vector<long> polygon;
      for (std::string_view tok = t.on_line(); !tok.empty(); tok = t.on_line()) {
        const std::optional<long> v = to_long(tok.substr(0, tok.find('/')));
        if (!v || *v == 0) fail(name, kind, "a face with a bad vertex index");
        // 1-based; negative indices count back from the vertices read so far.
        polygon.push_back(*v > 0 ? *v - 1 : long(soup.points.size()) + *v);
      }
      soup.polygons.push_back(std::move(polygon));
    }
    t.skip_line();
  }
  return soup;
}

}  // namespace sdfcontour::detail

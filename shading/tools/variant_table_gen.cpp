// variant_table_gen TABLE_JSON OUT_DIR: makes the code that follows from the
// one table of variants and parameters (shading/variant_table.json), so that
// a name, an id, a parameter or a default is written down once:
//   OUT_DIR/variant_table.glsl                  VARIANT_*, NMF_*, VariantParams and its unpacking
//   OUT_DIR/include/shimmer/shading/variant_table.h   Params<T>, the slot packing, the parameter list
//   OUT_DIR/variant_table.cpp                   ParamFields() and Variants()
// Each file is written to a temporary name and renamed, and left alone when
// its text is unchanged (so nothing downstream rebuilds). Bad tables stop
// the build with the entry and field named.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct TableError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const json& Field(const json& entry, const char* key, const std::string& where) {
  if (!entry.is_object() || !entry.contains(key)) throw TableError(where + ": no \"" + key + "\"");
  return entry.at(key);
}
std::string Text(const json& entry, const char* key, const std::string& where) {
  const json& v = Field(entry, key, where);
  if (!v.is_string()) throw TableError(where + "." + key + ": must be a string");
  return v.get<std::string>();
}
double Number(const json& v, const std::string& where) {
  if (!v.is_number()) throw TableError(where + ": must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw TableError(where + ": must be finite");
  return x;
}

// A C++ double literal that reads back as the same double.
std::string Literal(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  std::string s = buf;
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}
// A C++ string literal.
std::string Quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

struct Param {
  std::string name, meaning;
  double value, lo, hi;
};
struct FilterParam {
  std::string name, meaning;
  double value;
};
struct Filter {
  std::string name, glsl, summary, source;
  int id = 0;   // the variant id (a normal-map filter's: nmf * stride)
  int nmf = 0;  // normal-map filters: the NMF_* value
  std::vector<FilterParam> params;
  std::set<std::string> flags;
};
struct Table {
  int stride = 0;
  std::vector<Param> params;
  std::vector<Filter> filters, normal_map_filters;
};

const std::set<std::string> kFlags = {"widens_roughness", "ggx_only",    "glints",
                                       "reads_footprint",  "sg_light", "smooth_limit"};

Filter ReadFilter(const json& e, const std::string& where, const Table& t, bool normal_map) {
  Filter f;
  f.name = Text(e, "name", where);
  const std::string at = where + " (" + f.name + ")";
  f.glsl = Text(e, "glsl", at);
  f.summary = Text(e, "summary", at);
  f.source = Text(e, "source", at);
  const char* id_key = normal_map ? "nmf" : "id";
  const json& id = Field(e, id_key, at);
  if (!id.is_number_integer()) throw TableError(at + "." + id_key + ": must be an integer");
  if (normal_map) {
    f.nmf = id.get<int>();
    if (f.nmf < 1) throw TableError(at + ".nmf: must be at least 1 (0 is no normal-map filter)");
    f.id = f.nmf * t.stride;
  } else {
    f.id = id.get<int>();
    if (f.id < 0 || f.id >= t.stride) throw TableError(at + ".id: must be in [0, normal_map_filter_stride)");
  }
  const std::string prefix = normal_map ? "NMF_" : "VARIANT_";
  if (f.glsl.rfind(prefix, 0) != 0) throw TableError(at + ".glsl: must start with " + prefix);
  const json& ps = Field(e, "params", at);
  if (!ps.is_array()) throw TableError(at + ".params: must be an array");
  for (const json& p : ps) {
    FilterParam fp{Text(p, "name", at + ".params"), Text(p, "meaning", at + ".params"), 0};
    bool known = false;
    for (const Param& q : t.params) known = known || q.name == fp.name;
    if (!known) throw TableError(at + ".params: '" + fp.name + "' is not in the table's params");
    fp.value = Number(Field(p, "default", at), at + ".params." + fp.name + ".default");
    for (const Param& q : t.params)
      if (q.name == fp.name && (fp.value < q.lo || fp.value > q.hi))
        throw TableError(at + ".params." + fp.name + ".default: outside the parameter's range");
    f.params.push_back(fp);
  }
  const json& flags = Field(e, "flags", at);
  if (!flags.is_array()) throw TableError(at + ".flags: must be an array");
  for (const json& flag : flags) {
    if (!flag.is_string() || !kFlags.count(flag.get<std::string>()))
      throw TableError(at + ".flags: unknown flag " + flag.dump());
    f.flags.insert(flag.get<std::string>());
  }
  return f;
}

Table ReadTable(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw TableError("cannot read " + file.string());
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    throw TableError(std::string("not JSON: ") + e.what());
  }
  Table t;
  const json& stride = Field(j, "normal_map_filter_stride", "table");
  if (!stride.is_number_integer() || stride.get<int>() < 2) throw TableError("normal_map_filter_stride: must be >= 2");
  t.stride = stride.get<int>();
  for (const json& p : Field(j, "params", "table")) {
    Param q;
    q.name = Text(p, "name", "params");
    const std::string at = "params." + q.name;
    q.meaning = Text(p, "meaning", at);
    q.value = Number(Field(p, "default", at), at + ".default");
    const json& range = Field(p, "range", at);
    if (!range.is_array() || range.size() != 2) throw TableError(at + ".range: must be [lo, hi]");
    q.lo = Number(range[0], at + ".range"), q.hi = Number(range[1], at + ".range");
    if (!(q.lo <= q.value && q.value <= q.hi)) throw TableError(at + ".default: outside its range");
    t.params.push_back(q);
  }
  // The kernels carry the parameters in two vec4 slots (render.comp's Push).
  if (t.params.size() != 8) throw TableError("params: the kernels' two vec4 slots hold exactly 8 parameters");
  std::set<std::string> names, glsl;
  std::set<int> ids;
  auto add = [&](const Filter& f) {
    if (!names.insert(f.name).second) throw TableError("two entries are called " + f.name);
    if (!glsl.insert(f.glsl).second) throw TableError("two entries have the GLSL name " + f.glsl);
    if (!ids.insert(f.id).second) throw TableError(f.name + ": its id is taken");
  };
  for (const json& e : Field(j, "filters", "table")) add(t.filters.emplace_back(ReadFilter(e, "filters", t, false)));
  for (const json& e : Field(j, "normal_map_filters", "table"))
    add(t.normal_map_filters.emplace_back(ReadFilter(e, "normal_map_filters", t, true)));
  if (t.filters.empty() || t.filters.front().name != "none" || t.filters.front().id != 0)
    throw TableError("filters: the first entry must be none, id 0");
  return t;
}

const char* kHeader = "Generated from shading/variant_table.json by shading/tools/variant_table_gen.cpp: do not edit.";

std::string Glsl(const Table& t) {
  std::ostringstream s;
  s << "// " << kHeader << "\n\n// Geometric filters: a variant id's part below NMF_STRIDE.\n";
  int count = 0;
  for (const Filter& f : t.filters) {
    s << "const int " << f.glsl << " = " << f.id << ";  // " << f.name << "\n";
    count = std::max(count, f.id + 1);
  }
  s << "const int VARIANT_COUNT = " << count << ";\n\n";
  s << "// A variant id is a geometric filter plus NMF_STRIDE times a normal-map filter.\n";
  s << "const int NMF_STRIDE = " << t.stride << ";\n";
  s << "const int NMF_NONE = 0;  // level 0, bilinear: the surface the reference sees, at the pixel centre\n";
  int nmf_count = 1;
  for (const Filter& f : t.normal_map_filters) {
    s << "const int " << f.glsl << " = " << f.nmf << ";  // " << f.name << "\n";
    nmf_count = std::max(nmf_count, f.nmf + 1);
  }
  s << "const int NMF_COUNT = " << nmf_count << ";\n\n";
  s << "// The union of all variants' parameters; each variant reads its own.\nstruct VariantParams {\n";
  for (const Param& p : t.params) s << "  real " << p.name << ";  // " << p.meaning << "\n";
  s << "};\n\n";
  s << "// Fills VariantParams P from the two vec4 slots A and B the kernels are given\n"
       "// (render.comp's push constants, ndf_probe.comp's words), in the table's order.\n";
  s << "#define VARIANT_PARAMS_FROM_SLOTS(P, A, B)";
  static const char* kLanes[] = {"x", "y", "z", "w"};
  for (std::size_t i = 0; i < t.params.size(); ++i)
    s << " P." << t.params[i].name << " = " << (i < 4 ? "A." : "B.") << kLanes[i % 4] << ";";
  s << "\n";
  return s.str();
}

std::string Header(const Table& t) {
  std::ostringstream s;
  s << "// " << kHeader << "\n#pragma once\n\n#include <array>\n\nnamespace shimmer::shading {\n\n";
  s << "// The variant parameters, in the order of the kernels' slots, with their\n// defaults.\n";
  s << "template <class T>\nstruct Params {\n";
  for (const Param& p : t.params) s << "  T " << p.name << " = T(" << Literal(p.value) << ");  // " << p.meaning << "\n";
  s << "};\n\n";
  s << "// X(name) for each parameter, in slot order: code that copies or lists\n// the parameters field by field.\n";
  s << "#define SHIMMER_VARIANT_PARAMS(X)";
  for (const Param& p : t.params) s << " X(" << p.name << ")";
  s << "\n\ninline constexpr int kVariantParamCount = " << t.params.size() << ";\n";
  s << "inline constexpr int kNormalMapFilterStride = " << t.stride << ";\n\n";
  s << "// The slots the kernels read (VARIANT_PARAMS_FROM_SLOTS): two vec4.\n";
  s << "template <class T>\nstd::array<float, kVariantParamCount> PackVariantParams(const Params<T>& p) {\n  return {";
  for (std::size_t i = 0; i < t.params.size(); ++i) s << (i ? ", " : "") << "float(p." << t.params[i].name << ")";
  s << "};\n}\n\n";
  s << "// The same parameters in another precision.\n";
  s << "template <class T, class U>\nParams<T> ParamsCast(const Params<U>& p) {\n  Params<T> out;\n";
  for (const Param& p : t.params) s << "  out." << p.name << " = T(p." << p.name << ");\n";
  s << "  return out;\n}\n\n}  // namespace shimmer::shading\n";
  return s.str();
}

std::string Source(const Table& t) {
  std::ostringstream s;
  s << "// " << kHeader << "\n#include <vector>\n\n#include \"shimmer/shading/shading.h\"\n\n"
    << "namespace shimmer::shading {\nnamespace {\n\n";
  s << "// Upper bounds sit where a parameter stops changing anything, or, for the\n"
       "// kernel constants, far beyond what engines use (<= 1) yet low enough that\n"
       "// the renderer's float slots and their products stay finite.\n";
  s << "constexpr ParamField kParamFields[] = {\n";
  for (const Param& p : t.params)
    s << "    {" << Quoted(p.name) << ", &Params<double>::" << p.name << ", " << Literal(p.lo) << ", " << Literal(p.hi)
      << ", " << Quoted(p.meaning) << "},\n";
  s << "};\n\n";
  auto entry = [&](const Filter& f) {
    s << "      {.name = " << Quoted(f.name) << ",\n       .id = " << f.id << ",\n       .summary = " << Quoted(f.summary)
      << ",\n       .source = " << Quoted(f.source) << ",\n       .params = {";
    for (std::size_t i = 0; i < f.params.size(); ++i)
      s << (i ? ", " : "") << "{" << Quoted(f.params[i].name) << ", " << Literal(f.params[i].value) << ", "
        << Quoted(f.params[i].meaning) << "}";
    s << "},\n";
    const char* flags[] = {"widens_roughness", "ggx_only", "glints", "reads_footprint", "sg_light", "smooth_limit"};
    for (std::size_t i = 0; i < std::size(flags); ++i)
      s << "       ." << flags[i] << " = " << (f.flags.count(flags[i]) ? "true" : "false")
        << (i + 1 < std::size(flags) ? ",\n" : "},\n");
  };
  s << "std::vector<VariantInfo> Catalogue() {\n  return {\n";
  for (const Filter& f : t.filters) entry(f);
  s << "      // Normal-map filters (scenes with a normal map only); each combines with\n"
       "      // a geometric filter as GEOMETRIC+NAME.\n";
  for (const Filter& f : t.normal_map_filters) entry(f);
  s << "  };\n}\n\n}  // namespace\n\n";
  s << "std::span<const ParamField> ParamFields() { return kParamFields; }\n\n";
  s << "std::span<const VariantInfo> Variants() {\n  static const std::vector<VariantInfo> catalogue = Catalogue();\n"
       "  return catalogue;\n}\n\n}  // namespace shimmer::shading\n";
  return s.str();
}

void WriteIfChanged(const fs::path& file, const std::string& text) {
  {
    std::ifstream in(file, std::ios::binary);
    if (in && std::string((std::istreambuf_iterator<char>(in)), {}) == text) return;
  }
  fs::create_directories(file.parent_path());
  const fs::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out) throw TableError("cannot write " + tmp.string());
  }
  fs::rename(tmp, file);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: variant_table_gen TABLE_JSON OUT_DIR\n";
    return 2;
  }
  try {
    const Table t = ReadTable(argv[1]);
    const fs::path out = argv[2];
    WriteIfChanged(out / "variant_table.glsl", Glsl(t));
    WriteIfChanged(out / "include/shimmer/shading/variant_table.h", Header(t));
    WriteIfChanged(out / "variant_table.cpp", Source(t));
  } catch (const std::exception& e) {
    std::cerr << argv[1] << ": " << e.what() << "\n";
    return 2;
  }
  return 0;
}

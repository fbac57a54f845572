// User variant files: their shimmer-param declarations, parameter resolution
// and the UserParams struct the kernel compiles before the file.
#include "shimmer/shading/user_variant.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "shimmer/core/content_hash.h"
#include "shimmer/core/number_text.h"

namespace shimmer::shading {

namespace {

constexpr std::string_view kVariantTag = "shimmer-variant:";
constexpr std::string_view kParamTag = "shimmer-param:";
constexpr std::string_view kNoParamsTag = "shimmer-params:";

// Values travel to the GPU as float: larger magnitudes would not survive.
constexpr double kMaxMagnitude = 1e30;

// Names the generated struct would clash with, or the GLSL they would shadow.
const std::set<std::string, std::less<>> kReservedNames = {
    "bool",  "break", "const", "continue", "do",    "else",   "false",  "float", "for",   "if",
    "in",    "inout", "int",   "out",      "real",  "return", "struct", "true",  "uint",  "uniform",
    "vec2",  "vec3",  "vec4",  "void",     "while", "mat2",   "mat3",   "mat4",  "ivec2", "ivec3",
    "ivec4", "uvec2", "uvec3", "uvec4",    "double"};

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool IsIdentifier(std::string_view s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

// Reads a number at the front of `s` and drops it; false when there is none.
bool TakeNumber(std::string_view* s, double* value) {
  *s = Trim(*s);
  const std::string text(*s);
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  if (end == text.c_str()) return false;
  s->remove_prefix(std::size_t(end - text.c_str()));
  return true;
}

bool TakeToken(std::string_view* s, std::string_view token) {
  *s = Trim(*s);
  if (s->substr(0, token.size()) != token) return false;
  s->remove_prefix(token.size());
  return true;
}

constexpr std::string_view kParamSyntax = "expected 'shimmer-param: NAME = DEFAULT in [LO, HI]: meaning'";

// "k = 0.5 in [0, 4]: what k means" (the meaning is optional).
Result<UserParam> ParseParamLine(std::string_view rest) {
  using R = Result<UserParam>;
  UserParam p;
  rest = Trim(rest);
  std::size_t n = 0;
  while (n < rest.size() && (std::isalnum(static_cast<unsigned char>(rest[n])) || rest[n] == '_')) ++n;
  p.name = std::string(rest.substr(0, n));
  rest.remove_prefix(n);
  if (p.name.empty()) return R::Failure(std::string(kParamSyntax) + ": no parameter name");
  if (!IsIdentifier(p.name) || p.name.rfind("gl_", 0) == 0 || kReservedNames.count(p.name))
    return R::Failure("'" + p.name + "' is not a usable parameter name (a GLSL identifier, not a keyword or type)");
  if (!TakeToken(&rest, "=") || !TakeNumber(&rest, &p.default_value))
    return R::Failure(std::string(kParamSyntax) + ": " + p.name + " needs '= DEFAULT'");
  if (!TakeToken(&rest, "in") || !TakeToken(&rest, "[") || !TakeNumber(&rest, &p.lo) || !TakeToken(&rest, ",") ||
      !TakeNumber(&rest, &p.hi) || !TakeToken(&rest, "]"))
    return R::Failure(std::string(kParamSyntax) + ": " + p.name + " needs its range 'in [LO, HI]'");
  rest = Trim(rest);
  if (!rest.empty() && !TakeToken(&rest, ":"))
    return R::Failure(std::string(kParamSyntax) + ": unexpected '" + std::string(rest) + "' after the range");
  p.meaning = std::string(Trim(rest));
  for (double v : {p.default_value, p.lo, p.hi})
    if (!std::isfinite(v) || std::fabs(v) > kMaxMagnitude)
      return R::Failure(p.name + ": " + NumberText(v) + " is not a finite number of magnitude <= 1e30");
  if (!(p.lo <= p.hi))
    return R::Failure(p.name + ": the range [" + NumberText(p.lo) + ", " + NumberText(p.hi) + "] is empty");
  if (p.default_value < p.lo || p.default_value > p.hi)
    return R::Failure(p.name + ": the default " + NumberText(p.default_value) + " lies outside [" +
                      NumberText(p.lo) + ", " + NumberText(p.hi) + "]");
  return p;
}

// Binds each declared parameter to a VariantParams slot: one of the eight
// built-in names keeps its own slot (so p.sigma2 means what it says on the GPU side
// too), the others take the free slots in order.
void BindSlots(std::vector<UserParam>* params) {
  std::set<const ParamField*> used;
  for (UserParam& p : *params)
    if (const ParamField* f = FindParamField(p.name)) used.insert(p.slot = f);
  for (UserParam& p : *params) {
    if (p.slot) continue;
    for (const ParamField& f : ParamFields())
      if (!used.count(&f)) {
        used.insert(p.slot = &f);
        break;
      }
  }
}

// The eight built-in parameters, as a file without declarations reads them.
std::vector<UserParam> BuiltInParams() {
  std::vector<UserParam> params;
  for (const ParamField& f : ParamFields()) {
    UserParam p;
    p.name = std::string(f.name);
    p.default_value = Params<double>{}.*(f.member);
    p.lo = f.lo;
    p.hi = f.hi;
    p.meaning = std::string(f.meaning);
    p.slot = &f;
    params.push_back(std::move(p));
  }
  return params;
}

}  // namespace

Result<UserVariant> ParseUserVariant(std::string text, const std::string& file) {
  using R = Result<UserVariant>;
  UserVariant v;
  v.file = file;
  bool none = false;
  int none_line = 0;
  std::istringstream lines(text);
  int line_no = 0;
  for (std::string line; std::getline(lines, line);) {
    ++line_no;
    std::string_view s = Trim(line);
    if (s.substr(0, 2) != "//") continue;
    s = Trim(s.substr(2));
    const std::string at = file + ":" + std::to_string(line_no) + ": ";
    if (s.substr(0, kVariantTag.size()) == kVariantTag) {
      if (!v.summary.empty()) return R::Failure(at + "a second shimmer-variant line (one summary per file)");
      v.summary = std::string(Trim(s.substr(kVariantTag.size())));
    } else if (s.substr(0, kNoParamsTag.size()) == kNoParamsTag) {
      if (Trim(s.substr(kNoParamsTag.size())) != "none")
        return R::Failure(at + "expected 'shimmer-params: none' (declare each parameter with shimmer-param:)");
      none = true;
      none_line = line_no;
    } else if (s.substr(0, kParamTag.size()) == kParamTag) {
      auto p = ParseParamLine(s.substr(kParamTag.size()));
      if (!p) return R::Failure(at + p.error());
      if (FindUserParam(v, p->name)) return R::Failure(at + "parameter " + p->name + " is declared twice");
      if (int(v.params.size()) == kMaxUserParams)
        return R::Failure(at + "more than " + std::to_string(kMaxUserParams) +
                          " parameters: the renderer carries " + std::to_string(kMaxUserParams) + " per variant");
      p->line = line_no;
      v.params.push_back(std::move(*p));
    }
  }
  if (none && !v.params.empty())
    return R::Failure(file + ":" + std::to_string(none_line) +
                      ": 'shimmer-params: none' and shimmer-param lines in one file");
  v.declared = none || !v.params.empty();
  if (v.declared)
    BindSlots(&v.params);
  else
    v.params = BuiltInParams();
  v.content_hash = Fnv1a64Hex(text);
  v.text = std::move(text);
  return v;
}

Result<UserVariant> LoadUserVariant(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Result<UserVariant>::Failure(path + ": no such variant file");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) return Result<UserVariant>::Failure(path + ": cannot read the variant file", ErrorCode::kIo);
  return ParseUserVariant(text.str(), path);
}

const UserParam* FindUserParam(const UserVariant& v, std::string_view name) {
  for (const UserParam& p : v.params)
    if (p.name == name) return &p;
  return nullptr;
}

Result<UserParams> ResolveUserParams(const UserVariant& v,
                                     std::span<const std::pair<std::string, double>> overrides) {
  using R = Result<UserParams>;
  UserParams user;
  for (const UserParam& p : v.params) user.values.*(p.slot->member) = p.default_value;
  std::vector<double> values;
  for (const UserParam& p : v.params) values.push_back(p.default_value);
  for (const auto& [name, value] : overrides) {
    const UserParam* p = FindUserParam(v, name);
    if (!p) {
      std::string list;
      for (const UserParam& q : v.params) list += (list.empty() ? "" : ", ") + q.name;
      return R::Failure(v.file + " has no parameter '" + name + "'" +
                        (list.empty() ? " (it declares none)" : " (it declares: " + list + ")"));
    }
    if (!std::isfinite(value) || value < p->lo || value > p->hi)
      return R::Failure("parameter " + name + " of " + v.file + " must be >= " + NumberText(p->lo) + " and <= " +
                        NumberText(p->hi) + ", got " + NumberText(value));
    user.values.*(p->slot->member) = value;
    values[std::size_t(p - v.params.data())] = value;
  }
  for (std::size_t i = 0; i < v.params.size(); ++i) user.shown.push_back({v.params[i].name, values[i]});
  return user;
}

std::string UserParamsGlsl(const UserVariant& v) {
  std::ostringstream s;
  s << "// Generated from the shimmer-param lines of the user's variant file.\nstruct UserParams {\n";
  for (const UserParam& p : v.params) s << "  real " << p.name << ";\n";
  if (v.params.empty()) s << "  real unused_;  // the file declares no parameter; GLSL has no empty struct\n";
  s << "};\nUserParams userParams(VariantParams v) {\n  UserParams p;\n";
  for (const UserParam& p : v.params) s << "  p." << p.name << " = v." << p.slot->name << ";\n";
  if (v.params.empty()) s << "  p.unused_ = real(0);\n";
  s << "  return p;\n}\n";
  // For a call of a built-in variant (evalVariant): the declared values in
  // their slots, the built-in defaults in the others.
  const Params<double> defaults;
  s << "VariantParams variantParams(UserParams p) {\n  VariantParams v;\n";
  for (const ParamField& f : ParamFields()) {
    const UserParam* bound = nullptr;
    for (const UserParam& p : v.params) bound = p.slot == &f ? &p : bound;
    if (bound)
      s << "  v." << f.name << " = p." << bound->name << ";\n";
    else
      s << "  v." << f.name << " = real(" << NumberText(defaults.*(f.member)) << ");\n";
  }
  s << "  return v;\n}\n";
  return s.str();
}

std::string DescribeUserVariant(const UserVariant& v) {
  std::ostringstream s;
  s << v.file << ": " << (v.summary.empty() ? "a user variant (no shimmer-variant line)" : v.summary) << "\n";
  if (!v.declared) s << "  no shimmer-param lines: it may read the eight built-in parameters\n";
  if (v.params.empty()) s << "  parameters: none\n";
  for (const UserParam& p : v.params)
    s << "  " << p.name << " = " << NumberText(p.default_value) << " in [" << NumberText(p.lo) << ", "
      << NumberText(p.hi) << "]" << (p.meaning.empty() ? "" : ": " + p.meaning) << "\n";
  return s.str();
}

}  // namespace shimmer::shading

// glTF 2.0 assets (.gltf, .glb) through tinygltf (Debian's libtinygltf, a
// shared library: no TINYGLTF_IMPLEMENTATION here). Before tinygltf sees a
// file, this code checks what tinygltf trusts (the GLB container's lengths,
// buffer views inside their buffers), refuses required extensions, finds
// every external file and weighs the whole asset against the byte limit.
// Images are not decoded: a callback keeps their encoded bytes.
#include <tiny_gltf.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <limits>
#include <numeric>
#include <system_error>

#include "shimmer/core/number_text.h"
#include "shimmer/renderer/mesh_loading.h"

namespace shimmer::scene {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---- The GLB container and the JSON, before tinygltf ----

// glTF 2.0 spec, section 4 "GLB File Format Specification": a 12-byte header
// (magic, version, total length), then chunks of (length, type, bytes), JSON
// first and an optional BIN second; all little-endian, as the hosts are.
constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;
constexpr std::uint32_t kChunkBin = 0x004E4942;

std::uint32_t U32At(std::string_view bytes, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;
}

bool IsGlb(std::string_view bytes) { return bytes.size() >= 4 && U32At(bytes, 0) == kGlbMagic; }

struct GlbChunks {
  std::string_view json, bin;
  bool has_bin = false;
};

Result<GlbChunks> SplitGlb(const std::string& name, std::string_view bytes) {
  auto bad = [&](const std::string& why) { return Result<GlbChunks>::Failure(name + ": " + why); };
  const std::string size = std::to_string(bytes.size());
  if (bytes.size() < 20) return bad("truncated GLB: " + size + " bytes, too short for the header and a chunk");
  if (U32At(bytes, 4) != 2) return bad("GLB version " + std::to_string(U32At(bytes, 4)) + "; only 2 is supported");
  const std::uint64_t length = U32At(bytes, 8), json_length = U32At(bytes, 12);
  if (length != bytes.size())
    return bad((length > bytes.size() ? "truncated GLB: the header says " : "the GLB header says ") +
               std::to_string(length) + " bytes, the file has " + size);
  if (U32At(bytes, 16) != kChunkJson) return bad("the GLB's first chunk is not its JSON chunk");
  if (20 + json_length > length)
    return bad("truncated GLB: the JSON chunk says " + std::to_string(json_length) + " bytes, " +
               std::to_string(length - 20) + " follow");
  GlbChunks chunks;
  chunks.json = bytes.substr(20, json_length);
  const std::uint64_t next = 20 + json_length;
  if (next == length) return chunks;
  if (next + 8 > length) return bad("truncated GLB: a chunk header is cut off after the JSON chunk");
  const std::uint64_t bin_length = U32At(bytes, next);
  if (U32At(bytes, next + 4) != kChunkBin) return chunks;  // unknown chunks are skipped (section 4)
  if (next + 8 + bin_length > length)
    return bad("truncated GLB: the BIN chunk says " + std::to_string(bin_length) + " bytes, " +
               std::to_string(length - next - 8) + " follow");
  chunks.bin = bytes.substr(next + 8, bin_length);
  chunks.has_bin = true;
  return chunks;
}

// A URI's %XX escapes decoded (RFC 3986): how glTF writes file names with
// spaces and other reserved characters.
std::string UriDecoded(const std::string& uri) {
  std::string out;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

bool IsDataUri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }

// nlohmann's messages start with "[json.exception.parse_error.101] ".
std::string JsonMessage(const json::exception& e) {
  const std::string what = e.what();
  const std::size_t end = what.find("] ");
  return end == std::string::npos ? what : what.substr(end + 2);
}

struct Reference {
  std::string what;  // "buffer 0", "image 2"
  fs::path file;
};

Status CheckBufferViews(const std::string& name, const json& doc, const std::vector<std::uint64_t>& buffer_lengths) {
  const json views = doc.value("bufferViews", json::array());
  for (std::size_t i = 0; i < views.size(); ++i) {
    const std::string view = "bufferView " + std::to_string(i);
    const std::int64_t buffer = views[i].at("buffer").get<std::int64_t>();
    if (buffer < 0 || static_cast<std::size_t>(buffer) >= buffer_lengths.size())
      return Status::Failure(name + ": " + view + " refers to buffer " + std::to_string(buffer) +
                             ", which does not exist");
    const std::uint64_t offset = views[i].value("byteOffset", std::uint64_t{0});
    const std::uint64_t length = views[i].at("byteLength").get<std::uint64_t>();
    if (offset > buffer_lengths[buffer] || length > buffer_lengths[buffer] - offset)
      return Status::Failure(name + ": " + view + " (bytes " + std::to_string(offset) + " to " +
                             std::to_string(offset + length) + ") overruns buffer " + std::to_string(buffer) + " of " +
                             std::to_string(buffer_lengths[buffer]) + " bytes");
  }
  return Ok();
}

// Parses the JSON, refuses required extensions, checks buffers and buffer
// views, and returns the external files (which must exist).
Result<std::vector<Reference>> ScanJson(const std::string& name, std::string_view text, const fs::path& dir,
                                        const GlbChunks* glb) {
  using R = Result<std::vector<Reference>>;
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {
    return R::Failure(name + ": malformed JSON: " + JsonMessage(e));
  }
  std::vector<Reference> references;
  try {
    if (!doc.is_object()) return R::Failure(name + ": malformed glTF: the JSON is not an object");
    for (const json& extension : doc.value("extensionsRequired", json::array()))
      return R::Failure(name + ": unsupported required extension " + extension.get<std::string>() +
                        " (listed in extensionsRequired; shimmer implements none)");
    const json buffers = doc.value("buffers", json::array());
    std::vector<std::uint64_t> lengths;
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      const std::string buffer = "buffer " + std::to_string(i);
      lengths.push_back(buffers[i].at("byteLength").get<std::uint64_t>());
      if (buffers[i].contains("uri")) {
        const std::string uri = buffers[i]["uri"].get<std::string>();
        if (!IsDataUri(uri)) references.push_back({buffer, dir / UriDecoded(uri)});
      } else if (!glb || i != 0 || !glb->has_bin) {
        return R::Failure(name + ": " + buffer + " has no uri and is not a GLB's BIN chunk");
      } else if (lengths.back() > glb->bin.size()) {
        return R::Failure(name + ": truncated GLB: " + buffer + " says " + std::to_string(lengths.back()) +
                          " bytes, the BIN chunk has " + std::to_string(glb->bin.size()));
      }
    }
    if (Status s = CheckBufferViews(name, doc, lengths); !s) return s.failure();
    const json images = doc.value("images", json::array());
    for (std::size_t i = 0; i < images.size(); ++i)
      if (images[i].contains("uri") && !IsDataUri(images[i]["uri"].get<std::string>()))
        references.push_back({"image " + std::to_string(i), dir / UriDecoded(images[i]["uri"].get<std::string>())});
  } catch (const json::exception& e) {
    return R::Failure(name + ": malformed glTF: " + JsonMessage(e));
  }
  for (const Reference& r : references) {
    std::error_code error;
    if (!fs::is_regular_file(r.file, error))
      return R::Failure(name + ": " + r.what + "'s file " + r.file.string() + " is missing");
  }
  return references;
}

Status CheckFileBytes(const std::string& name, std::uint64_t file_bytes, const std::vector<Reference>& references,
                      std::uint64_t max_bytes) {
  std::uint64_t total = file_bytes;
  for (const Reference& r : references) {
    std::error_code error;
    const std::uintmax_t size = fs::file_size(r.file, error);
    total += error ? 0 : size;  // tinygltf reports a file it cannot read
  }
  if (total <= max_bytes) return Ok();
  return Status::Failure(name + ": the asset's files (the file, its buffers and images) take " + std::to_string(total) +
                         " bytes, over the limit of " + std::to_string(max_bytes) + " bytes (LoadOptions::max_bytes)");
}

// ---- tinygltf ----

// The image callback: keep the encoded bytes, decode nothing.
bool KeepEncodedImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + size);
  return true;
}

Result<tinygltf::Model> ParseModel(const std::string& name, const std::string& bytes, const fs::path& dir,
                                   std::vector<std::string>& warnings) {
  if (bytes.size() > std::numeric_limits<unsigned int>::max())
    return Result<tinygltf::Model>::Failure(name + ": over 4 GiB, more than tinygltf reads");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&KeepEncodedImage, nullptr);
  tinygltf::Model model;
  std::string error, warning;
  bool ok = false;
  try {
    const auto size = static_cast<unsigned int>(bytes.size());
    ok = IsGlb(bytes)
             ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                           reinterpret_cast<const unsigned char*>(bytes.data()), size, dir.string())
             : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(), size, dir.string());
  } catch (const std::exception& e) {
    error = e.what();
  }
  for (std::size_t start = 0; start < warning.size();) {
    const std::size_t end = std::min(warning.find('\n', start), warning.size());
    if (end > start) warnings.push_back(name + ": " + warning.substr(start, end - start));
    start = end + 1;
  }
  if (!ok)
    return Result<tinygltf::Model>::Failure(name +
                                            ": not a valid glTF 2.0 asset: " + error.substr(0, error.find('\n')));
  return model;
}

// ---- Accessors ----

struct AccessorView {
  const std::uint8_t* data = nullptr;
  std::size_t stride = 0, count = 0;
  int component_type = 0;
  bool normalized = false;
};

Result<AccessorView> ViewAccessor(const tinygltf::Model& model, int index, int type, const std::string& what) {
  using R = Result<AccessorView>;
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size())
    return R::Failure(what + ": accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = model.accessors[index];
  const std::string where = what + " (accessor " + std::to_string(index) + ")";
  if (a.sparse.isSparse) return R::Failure(where + ": sparse accessors are not supported");
  if (a.type != type)
    return R::Failure(where + ": type " + std::to_string(a.type) + ", expected " + std::to_string(type));
  const int component_size = tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(a.componentType));
  if (component_size <= 0) return R::Failure(where + ": unknown component type " + std::to_string(a.componentType));
  const std::size_t element = static_cast<std::size_t>(component_size) * tinygltf::GetNumComponentsInType(type);
  AccessorView view{nullptr, element, a.count, a.componentType, a.normalized};
  if (a.count == 0) return view;
  // Without a bufferView an accessor is all zeros, of any count: useful only
  // under sparse values, and a way to ask for unbounded memory.
  if (a.bufferView < 0) return R::Failure(where + ": no bufferView (all zeros) is not supported");
  if (static_cast<std::size_t>(a.bufferView) >= model.bufferViews.size())
    return R::Failure(where + ": bufferView " + std::to_string(a.bufferView) + " does not exist");
  const tinygltf::BufferView& bv = model.bufferViews[a.bufferView];
  if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model.buffers.size())
    return R::Failure(where + ": buffer " + std::to_string(bv.buffer) + " does not exist");
  const std::vector<unsigned char>& buffer = model.buffers[bv.buffer].data;
  if (bv.byteStride != 0) view.stride = bv.byteStride;
  if (view.stride < element)
    return R::Failure(where + ": byteStride " + std::to_string(view.stride) + " is shorter than an element");
  const std::size_t room = bv.byteLength > a.byteOffset ? bv.byteLength - a.byteOffset : 0;
  if (room < element || (a.count - 1) > (room - element) / view.stride || bv.byteOffset > buffer.size() ||
      bv.byteLength > buffer.size() - bv.byteOffset)
    return R::Failure(where + ": " + std::to_string(a.count) + " elements of stride " + std::to_string(view.stride) +
                      " from byte " + std::to_string(a.byteOffset) + " overrun bufferView " +
                      std::to_string(a.bufferView) + " of " + std::to_string(bv.byteLength) + " bytes");
  view.data = buffer.data() + bv.byteOffset + a.byteOffset;
  return view;
}

// Float, or (where allowed) normalised unsigned bytes and shorts, c / 255
// and c / 65535 (glTF 2.0 spec, "Animations", normalised integers).
Status CheckComponents(const AccessorView& view, bool allow_normalized, const std::string& what) {
  const int t = view.component_type;
  if (t == TINYGLTF_COMPONENT_TYPE_FLOAT) return Ok();
  if (allow_normalized && view.normalized &&
      (t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
    return Ok();
  return Status::Failure(what + ": component type " + std::to_string(t) + (view.normalized ? "" : " unnormalised") +
                         (allow_normalized ? "; glTF 2.0 allows float or normalised unsigned byte or short here"
                                           : "; glTF 2.0 allows only float here"));
}

template <int N>
std::vector<glm::vec<N, float>> ReadVectors(const AccessorView& view) {
  std::vector<glm::vec<N, float>> out(view.count, glm::vec<N, float>(0));
  for (std::size_t i = 0; i < view.count; ++i) {
    const std::uint8_t* p = view.data + i * view.stride;
    for (int c = 0; c < N; ++c) {
      if (view.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT) {
        std::memcpy(&out[i][c], p + 4 * c, 4);
      } else if (view.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
        out[i][c] = p[c] / 255.0f;
      } else {
        std::uint16_t v;
        std::memcpy(&v, p + 2 * c, 2);
        out[i][c] = v / 65535.0f;
      }
    }
  }
  return out;
}

Result<std::vector<std::uint32_t>> ReadIndices(const tinygltf::Model& model, int index, const std::string& what) {
  Result<AccessorView> view = ViewAccessor(model, index, TINYGLTF_TYPE_SCALAR, what);
  if (!view) return view.failure();
  const int t = view->component_type;
  if (t != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && t != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      t != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    return Result<std::vector<std::uint32_t>>::Failure(what + ": component type " + std::to_string(t) +
                                                       "; indices are unsigned bytes, shorts or ints");
  const auto size = static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(t)));
  std::vector<std::uint32_t> out(view->count, 0);
  for (std::size_t i = 0; i < view->count; ++i) std::memcpy(&out[i], view->data + i * view->stride, size);
  return out;  // little-endian: the low bytes land first
}

// ---- Primitives, materials, nodes ----

constexpr const char* kModeNames[] = {"POINTS",    "LINES",          "LINE_LOOP",   "LINE_STRIP",
                                      "TRIANGLES", "TRIANGLE_STRIP", "TRIANGLE_FAN"};

template <int N>
Status ReadAttribute(const tinygltf::Model& model, const tinygltf::Primitive& primitive, const char* attribute,
                     const std::string& where, std::size_t count, std::vector<glm::vec<N, float>>& out) {
  const auto it = primitive.attributes.find(attribute);
  if (it == primitive.attributes.end()) return Ok();
  const std::string what = where + " " + attribute;
  const int type = N == 2 ? TINYGLTF_TYPE_VEC2 : N == 3 ? TINYGLTF_TYPE_VEC3 : TINYGLTF_TYPE_VEC4;
  Result<AccessorView> view = ViewAccessor(model, it->second, type, what);
  if (!view) return view.failure();
  if (Status s = CheckComponents(*view, N == 2, what); !s) return s;
  if (count != std::numeric_limits<std::size_t>::max() && view->count != count)
    return Status::Failure(what + ": " + std::to_string(view->count) + " elements, POSITION has " +
                           std::to_string(count));
  out = ReadVectors<N>(*view);
  return Ok();
}

Result<TriangleMesh> ReadPrimitive(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                                   const std::string& where) {
  using R = Result<TriangleMesh>;
  const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES)
    return R::Failure(where + ": mode " + std::to_string(mode) +
                      (mode <= 6 ? std::string(" (") + kModeNames[mode] + ")" : "") +
                      "; only TRIANGLES (4) is supported");
  if (!primitive.attributes.count("POSITION")) return R::Failure(where + ": no POSITION attribute");
  constexpr std::size_t kAnyCount = std::numeric_limits<std::size_t>::max();
  TriangleMesh mesh;
  if (Status s = ReadAttribute<3>(model, primitive, "POSITION", where, kAnyCount, mesh.positions); !s)
    return s.failure();
  const std::size_t n = mesh.positions.size();
  for (Status s : {ReadAttribute<3>(model, primitive, "NORMAL", where, n, mesh.normals),
                   ReadAttribute<4>(model, primitive, "TANGENT", where, n, mesh.tangents),
                   ReadAttribute<2>(model, primitive, "TEXCOORD_0", where, n, mesh.uv0)})
    if (!s) return s.failure();
  if (primitive.indices >= 0) {
    Result<std::vector<std::uint32_t>> indices = ReadIndices(model, primitive.indices, where + " indices");
    if (!indices) return indices.failure();
    mesh.indices = std::move(*indices);
  } else {
    mesh.indices.resize(n);  // glTF 2.0 spec, "Meshes": no indices, the vertices in order
    std::iota(mesh.indices.begin(), mesh.indices.end(), 0u);
  }
  return mesh;
}

// Every image as a MeshTexture: a file path, or the embedded bytes moved out
// of the model once so that every mesh using the image shares them.
std::vector<MeshTexture> ImageTextures(tinygltf::Model& model, const fs::path& dir) {
  std::vector<MeshTexture> textures;
  for (std::size_t i = 0; i < model.images.size(); ++i) {
    tinygltf::Image& image = model.images[i];
    MeshTexture t;
    t.image = static_cast<int>(i);
    t.mime_type = image.mimeType;
    if (!image.uri.empty() && !IsDataUri(image.uri))
      t.file = dir / UriDecoded(image.uri);  // tinygltf read it; the path is what a later step needs
    else
      t.encoded = std::make_shared<const std::vector<std::uint8_t>>(std::move(image.image));
    textures.push_back(std::move(t));
  }
  return textures;
}

Result<MeshTexture> TextureOf(const tinygltf::Model& model, const std::vector<MeshTexture>& images, int texture,
                              int texcoord, const std::string& what, std::vector<std::string>& warnings) {
  if (texture < 0) return MeshTexture{};
  if (static_cast<std::size_t>(texture) >= model.textures.size())
    return Result<MeshTexture>::Failure(what + ": texture " + std::to_string(texture) + " does not exist");
  const int source = model.textures[texture].source;
  if (source < 0) {
    warnings.push_back(what + ": texture " + std::to_string(texture) +
                       " has no core source image (an extension's format?); ignored");
    return MeshTexture{};
  }
  if (static_cast<std::size_t>(source) >= images.size())
    return Result<MeshTexture>::Failure(what + ": image " + std::to_string(source) + " does not exist");
  if (texcoord != 0)
    warnings.push_back(what + ": reads TEXCOORD_" + std::to_string(texcoord) +
                       "; only TEXCOORD_0 is loaded, which it will be sampled with");
  return images[source];
}

Result<MeshMaterial> MaterialOf(const tinygltf::Model& model, const std::vector<MeshTexture>& images, int index,
                                const std::string& where, std::vector<std::string>& warnings) {
  using R = Result<MeshMaterial>;
  MeshMaterial m;
  if (index < 0) return m;  // glTF's default material: the factors' defaults
  if (static_cast<std::size_t>(index) >= model.materials.size())
    return R::Failure(where + ": material " + std::to_string(index) + " does not exist");
  const tinygltf::Material& source = model.materials[index];
  const std::string what = where + " material " + std::to_string(index) + " '" + source.name + "'";
  const tinygltf::PbrMetallicRoughness& pbr = source.pbrMetallicRoughness;
  m.name = source.name;
  m.roughness = pbr.roughnessFactor;
  m.metallic = pbr.metallicFactor;
  if (!(m.roughness >= 0 && m.roughness <= 1) || !(m.metallic >= 0 && m.metallic <= 1))
    return R::Failure(what + ": roughnessFactor " + NumberText(m.roughness) + " or metallicFactor " +
                      NumberText(m.metallic) + " is outside [0, 1]");
  if (pbr.baseColorFactor.size() == 4) m.base_color = glm::make_vec4(pbr.baseColorFactor.data());
  Result<MeshTexture> normal = TextureOf(model, images, source.normalTexture.index, source.normalTexture.texCoord,
                                         what + " normalTexture", warnings);
  if (!normal) return normal.failure();
  m.normal_texture = std::move(*normal);
  m.normal_scale = source.normalTexture.scale;
  Result<MeshTexture> mr =
      TextureOf(model, images, pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                what + " metallicRoughnessTexture", warnings);
  if (!mr) return mr.failure();
  m.metallic_roughness_texture = std::move(*mr);
  return m;
}

// A node's matrix, or T * R * S (glTF 2.0 spec, "Transformations").
Result<glm::dmat4> LocalTransform(const tinygltf::Node& node, const std::string& where) {
  using R = Result<glm::dmat4>;
  glm::dmat4 m(1);
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16) return R::Failure(where + ": a matrix needs 16 numbers");
    m = glm::make_mat4(node.matrix.data());  // column-major, as glm
  } else {
    if ((!node.translation.empty() && node.translation.size() != 3) ||
        (!node.rotation.empty() && node.rotation.size() != 4) || (!node.scale.empty() && node.scale.size() != 3))
      return R::Failure(where + ": translation, rotation and scale need 3, 4 and 3 numbers");
    const glm::dvec3 t = node.translation.empty() ? glm::dvec3(0) : glm::make_vec3(node.translation.data());
    const glm::dvec3 s = node.scale.empty() ? glm::dvec3(1) : glm::make_vec3(node.scale.data());
    const auto& r = node.rotation;
    glm::dquat q = r.empty() ? glm::dquat(1, 0, 0, 0) : glm::dquat(r[3], r[0], r[1], r[2]);  // glTF: x, y, z, w
    if (glm::length(q) > 0) q = glm::normalize(q);
    m = glm::translate(glm::dmat4(1), t) * glm::mat4_cast(q) * glm::scale(glm::dmat4(1), s);
  }
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 4; ++k)
      if (!std::isfinite(m[c][k])) return R::Failure(where + ": a non-finite transform");
  return m;
}

struct Instance {
  int node = 0, mesh = 0;
  glm::dmat4 world{1};
};

std::vector<int> RootNodes(const tinygltf::Model& model) {
  if (!model.scenes.empty())
    return model.scenes[model.defaultScene >= 0 ? model.defaultScene : 0].nodes;  // range checked by the caller
  std::vector<char> child(model.nodes.size(), 0);
  for (const tinygltf::Node& n : model.nodes)
    for (int c : n.children)
      if (c >= 0 && static_cast<std::size_t>(c) < child.size()) child[c] = 1;
  std::vector<int> roots;
  for (std::size_t i = 0; i < child.size(); ++i)
    if (!child[i]) roots.push_back(static_cast<int>(i));
  return roots;
}

// The nodes with a mesh under the chosen scene's roots, depth first, with
// their world transforms; an explicit stack, so a deep chain cannot overflow.
Result<std::vector<Instance>> MeshInstances(const tinygltf::Model& model, const std::string& name) {
  using R = Result<std::vector<Instance>>;
  if (model.defaultScene >= static_cast<int>(model.scenes.size()))
    return R::Failure(name + ": the default scene " + std::to_string(model.defaultScene) + " does not exist");
  std::vector<std::pair<int, glm::dmat4>> stack;
  const std::vector<int> roots = RootNodes(model);
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1));
  std::vector<char> visited(model.nodes.size(), 0);
  std::vector<Instance> instances;
  while (!stack.empty()) {
    const auto [index, parent] = stack.back();
    stack.pop_back();
    const std::string where = name + ": node " + std::to_string(index);
    if (index < 0 || static_cast<std::size_t>(index) >= model.nodes.size())
      return R::Failure(where + " does not exist");
    if (visited[index]++)
      return R::Failure(where + " is reached twice; the node hierarchy must be a forest (glTF 2.0 spec, \"Nodes\")");
    const tinygltf::Node& node = model.nodes[index];
    Result<glm::dmat4> local = LocalTransform(node, where);
    if (!local) return local.failure();
    const glm::dmat4 world = parent * *local;
    if (node.mesh >= 0 && static_cast<std::size_t>(node.mesh) >= model.meshes.size())
      return R::Failure(where + ": mesh " + std::to_string(node.mesh) + " does not exist");
    if (node.mesh >= 0) instances.push_back({index, node.mesh, world});
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
  }
  return instances;
}

// Each distinct entry once, in order of first appearance.
template <class T>
std::vector<T> Deduplicated(const std::vector<T>& values) {
  std::vector<T> out;
  for (const T& v : values)
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  return out;
}

std::vector<fs::path> FileList(const fs::path& file, const std::vector<Reference>& references) {
  std::vector<fs::path> files = {file};
  for (const Reference& r : references) files.push_back(r.file);
  return Deduplicated(files);
}

// The checked JSON's external files, from a .gltf or a GLB.
Result<std::vector<Reference>> Scan(const std::string& name, const std::string& bytes, const fs::path& dir) {
  if (!IsGlb(bytes)) return ScanJson(name, bytes, dir, nullptr);
  Result<GlbChunks> chunks = SplitGlb(name, bytes);
  if (!chunks) return chunks.failure();
  return ScanJson(name, chunks->json, dir, &*chunks);
}

// One instance's primitives into `asset`, each a checked, completed mesh.
Status AddInstance(const tinygltf::Model& model, const std::vector<MeshTexture>& images, const Instance& instance,
                   const std::string& name, std::uint64_t max_bytes, std::uint64_t& bytes, MeshAsset& asset) {
  const tinygltf::Mesh& mesh = model.meshes[instance.mesh];
  for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
    const std::string label = "mesh " + std::to_string(instance.mesh) + " '" + mesh.name + "' primitive " +
                              std::to_string(p) + " (node " + std::to_string(instance.node) + ")";
    const std::string where = name + ": " + label;
    Result<TriangleMesh> triangles = ReadPrimitive(model, mesh.primitives[p], where);
    if (!triangles) return triangles.failure();
    Result<MeshMaterial> material = MaterialOf(model, images, mesh.primitives[p].material, where, asset.warnings);
    if (!material) return material.failure();
    triangles->name = label;
    triangles->material = std::move(*material);
    if (!TransformMesh(instance.world, *triangles)) {
      asset.warnings.push_back(where + ": the node's transform is singular (a zero scale); left out");
      continue;
    }
    if (Status s = CompleteMesh(where, *triangles, asset.warnings); !s) return s;
    bytes += triangles->byte_size();
    if (bytes > max_bytes)
      return Status::Failure(name + ": the meshes take over " + std::to_string(max_bytes) +
                             " bytes, the limit (LoadOptions::max_bytes)");
    asset.meshes.push_back(std::move(*triangles));
  }
  return Ok();
}

}  // namespace

Result<MeshAsset> LoadGltfAsset(const fs::path& file, const LoadOptions& options) {
  const std::string name = file.string();
  const fs::path dir = file.parent_path();
  Result<std::string> bytes = ReadAssetFile(file, options.max_bytes);
  if (!bytes) return bytes.failure();
  Result<std::vector<Reference>> references = Scan(name, *bytes, dir);
  if (!references) return references.failure();
  if (Status s = CheckFileBytes(name, bytes->size(), *references, options.max_bytes); !s) return s.failure();
  MeshAsset asset;
  asset.file = file;
  asset.files = FileList(file, *references);
  Result<tinygltf::Model> model = ParseModel(name, *bytes, dir, asset.warnings);
  if (!model) return model.failure();
  *bytes = std::string();  // the model holds what is needed now
  const std::vector<MeshTexture> images = ImageTextures(*model, dir);
  Result<std::vector<Instance>> instances = MeshInstances(*model, name);
  if (!instances) return instances.failure();
  std::uint64_t mesh_bytes = 0;
  for (const Instance& instance : *instances)
    if (Status s = AddInstance(*model, images, instance, name, options.max_bytes, mesh_bytes, asset); !s)
      return s.failure();
  if (asset.meshes.empty()) return Result<MeshAsset>::Failure(name + ": no triangles (the scene places no mesh)");
  asset.warnings = Deduplicated(asset.warnings);
  return asset;
}

Result<std::vector<fs::path>> GltfAssetFiles(const fs::path& file) {
  Result<std::string> bytes = ReadAssetFile(file, LoadOptions{}.max_bytes);
  if (!bytes) return bytes.failure();
  Result<std::vector<Reference>> references = Scan(file.string(), *bytes, file.parent_path());
  if (!references) return references.failure();
  return FileList(file, *references);
}

}  // namespace shimmer::scene

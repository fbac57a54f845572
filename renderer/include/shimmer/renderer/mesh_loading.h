// Triangle-mesh assets from files: glTF 2.0 (.gltf with external or data-URI
// buffers, .glb) through tinygltf, OBJ with its MTL files through
// tinyobjloader, into the MeshAsset of triangle_mesh.h.
//
// glTF: the default scene (else scene 0, else every root node), each node's
// world transform applied; TRIANGLES primitives only; POSITION, NORMAL,
// TANGENT, TEXCOORD_0 (float or normalised integers), indices of 8, 16 or 32
// bits or none; the metallic-roughness material with its normal texture.
// Any extension in extensionsRequired is refused (none is implemented).
// OBJ: positions, normals, uvs, polygons split into fans, one mesh per
// material; MTL Pr (else Ns) as roughness, Pm, Kd and d, map_Pr, and norm
// (else map_Bump or bump) as the normal texture.
//
// Every error is one message that names the file and the problem; a missing
// buffer, image or MTL file is an error that names both files.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/renderer/triangle_mesh.h"

namespace shimmer::scene {

struct LoadOptions {
  // The most bytes an asset may read (its file, buffers, images and MTL
  // files) and, separately, the most its meshes' arrays may take: an asset
  // over either is refused before it exhausts the host's memory.
  std::uint64_t max_bytes = std::uint64_t{2} << 30;
};

// Chooses the loader by the extension (.gltf, .glb, .obj, any case); any
// other extension is an error that names it.
Result<MeshAsset> LoadMeshAsset(const std::filesystem::path& file, const LoadOptions& options = {});

Result<MeshAsset> LoadGltfAsset(const std::filesystem::path& file, const LoadOptions& options = {});
Result<MeshAsset> LoadObjAsset(const std::filesystem::path& file, const LoadOptions& options = {});

// `file` and every file it refers to (glTF buffers and images, OBJ's MTL
// files and the textures they name), without loading any geometry: what a
// cache keyed by content must read. Errors for a missing file, a malformed
// glTF JSON or GLB container, and an unknown extension.
Result<std::vector<std::filesystem::path>> AssetFiles(const std::filesystem::path& file);
Result<std::vector<std::filesystem::path>> GltfAssetFiles(const std::filesystem::path& file);
Result<std::vector<std::filesystem::path>> ObjAssetFiles(const std::filesystem::path& file);

// 16 hex digits (FNV-1a, content_hash.h) over the bytes of AssetFiles(file)
// in order: equal for equal content wherever the files lie, so a BVH cache
// can key by it. Files are read one at a time, each up to `max_bytes`.
Result<std::string> AssetContentHash(const std::filesystem::path& file, const LoadOptions& options = {});

// The whole file; an error naming it when it is missing, unreadable or
// larger than max_bytes.
Result<std::string> ReadAssetFile(const std::filesystem::path& file, std::uint64_t max_bytes);

}  // namespace shimmer::scene

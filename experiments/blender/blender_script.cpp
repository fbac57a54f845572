#include "shimmer/experiments/blender_script.h"

#include <cmath>
#include <string_view>

#include "shimmer/core/number_text.h"

namespace shimmer::experiments {

namespace {

constexpr double kPi = 3.14159265358979323846;

nlohmann::json Vec(glm::dvec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); }

// The script after its data block. Everything the shot needs comes from SHOT;
// the Python only converts frames and builds Cycles objects. Conventions it
// relies on (each checked against Cycles 3.4, see docs/renderer.md):
//  - shimmer is y-up right-handed, Blender z-up right-handed: (x, y, z) maps
//    to (x, -z, y), a rotation, so handedness and normals are kept;
//  - a sun lamp of angle 0 is a delta light with strength = irradiance; a
//    point lamp of radius 0 and power P has intensity P / (4 pi);
//  - the Glossy BSDF squares its roughness, hence roughness = sqrt(alpha); it
//    has no Fresnel: the colour is Schlick's F(v.h) built from the incoming
//    and light directions, exact for a delta light with direct light only;
//  - shimmer traces no shadow rays, so lamps cast no shadows here either.
constexpr std::string_view kScriptBody = R"PY(

import argparse
import math
import os
import sys

import bpy
from mathutils import Matrix, Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender -b --factory-startup -P scene.py --",
                                description="Render shimmer's shot " + SHOT["scene"] + " with Cycles")
    p.add_argument("--out", required=True, help="output OpenEXR file (linear float RGB)")
    p.add_argument("--spp", type=int, default=SHOT["default_spp"], help="samples per pixel")
    p.add_argument("--threads", type=int, default=0, help="render threads (0: all cores)")
    p.add_argument("--seed", type=int, default=0, help="Cycles sampling seed")
    a = p.parse_args(argv)
    if a.spp < 1:
        p.error("--spp must be >= 1")
    return a


def zup(v):
    """shimmer's y-up coordinates to Blender's z-up ones (a rotation about x)."""
    return Vector((v[0], -v[2], v[1]))


def clear_scene():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.lights, bpy.data.cameras,
                       bpy.data.materials, bpy.data.node_groups, bpy.data.worlds):
        for item in list(collection):
            collection.remove(item)


def math_node(nt, op, a, b=None, clamp=False):
    n = nt.nodes.new("ShaderNodeMath")
    n.operation = op
    n.use_clamp = clamp
    for i, x in enumerate((a, b)):
        if x is None:
            continue
        if isinstance(x, (int, float)):
            n.inputs[i].default_value = x
        else:
            nt.links.new(x, n.inputs[i])
    return n.outputs[0]


def vector_node(nt, op, a, b=None):
    n = nt.nodes.new("ShaderNodeVectorMath")
    n.operation = op
    for i, x in enumerate((a, b)):
        if x is None:
            continue
        if isinstance(x, (tuple, list, Vector)):
            n.inputs[i].default_value = tuple(x)
        else:
            nt.links.new(x, n.inputs[i])
    return n.outputs["Value"] if op in ("DOT_PRODUCT", "LENGTH") else n.outputs["Vector"]


def make_material():
    m = SHOT["material"]
    light = SHOT["light"]
    mat = bpy.data.materials.new("shimmer")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    view = geo.outputs["Incoming"]  # unit vector towards the eye
    if light["type"] == "sun":
        to_light = tuple(zup(light["direction"]))
    else:
        to_light = vector_node(nt, "NORMALIZE",
                               vector_node(nt, "SUBTRACT", tuple(zup(light["position"])), geo.outputs["Position"]))
    half = vector_node(nt, "NORMALIZE", vector_node(nt, "ADD", view, to_light))
    one_minus = math_node(nt, "SUBTRACT", 1.0, vector_node(nt, "DOT_PRODUCT", view, half), clamp=True)
    m5 = math_node(nt, "POWER", one_minus, 5.0)
    f0 = m["f0"]
    scaled = nt.nodes.new("ShaderNodeVectorMath")
    scaled.operation = "SCALE"
    scaled.inputs[0].default_value = (1 - f0[0], 1 - f0[1], 1 - f0[2])
    nt.links.new(m5, scaled.inputs["Scale"])
    fresnel = vector_node(nt, "ADD", scaled.outputs["Vector"], tuple(f0))
    glossy = nt.nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = "GGX" if m["ndf"] == "ggx" else "BECKMANN"
    glossy.inputs["Roughness"].default_value = m["roughness"]
    nt.links.new(fresnel, glossy.inputs["Color"])
    shader = glossy.outputs["BSDF"]
    if not SHOT["specular_only"] and max(m["albedo"]) > 0:
        diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (*m["albedo"], 1.0)
        diffuse.inputs["Roughness"].default_value = 0.0
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader, add.inputs[0])
        nt.links.new(diffuse.outputs["BSDF"], add.inputs[1])
        shader = add.outputs["Shader"]
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    nt.links.new(shader, out.inputs["Surface"])
    return mat


def add_object(name, data, mat):
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    if mat is not None and hasattr(data, "materials"):
        data.materials.append(mat)
    return obj


def add_spheres(spheres, mat):
    """Exact analytic spheres: a Geometry Nodes point cloud, one point a sphere."""
    me = bpy.data.meshes.new("sphere_centres")
    me.vertices.add(len(spheres))
    me.vertices.foreach_set("co", [c for s in spheres for c in zup(s[:3])])
    radius = me.attributes.new("radius", "FLOAT", "POINT")
    radius.data.foreach_set("value", [s[3] for s in spheres])
    me.update()
    ng = bpy.data.node_groups.new("spheres", "GeometryNodeTree")
    ng.inputs.new("NodeSocketGeometry", "Geometry")
    ng.outputs.new("NodeSocketGeometry", "Geometry")
    gin = ng.nodes.new("NodeGroupInput")
    gout = ng.nodes.new("NodeGroupOutput")
    points = ng.nodes.new("GeometryNodeMeshToPoints")
    points.mode = "VERTICES"
    attr = ng.nodes.new("GeometryNodeInputNamedAttribute")
    attr.data_type = "FLOAT"
    attr.inputs["Name"].default_value = "radius"
    set_mat = ng.nodes.new("GeometryNodeSetMaterial")
    set_mat.inputs["Material"].default_value = mat
    ng.links.new(gin.outputs[0], points.inputs["Mesh"])
    ng.links.new([s for s in attr.outputs if s.type == "VALUE"][0], points.inputs["Radius"])
    ng.links.new(points.outputs["Points"], set_mat.inputs["Geometry"])
    ng.links.new(set_mat.outputs["Geometry"], gout.inputs[0])
    obj = add_object("spheres", me, None)
    obj.modifiers.new("spheres", "NODES").node_group = ng


def add_cylinders(capsules, mat, segments=128):
    """The capsules' cylinders as smooth-shaded meshes (their caps are spheres)."""
    verts, faces = [], []
    for c in capsules:
        a, b, r = zup(c[0:3]), zup(c[3:6]), c[6]
        axis = (b - a).normalized()
        u = axis.orthogonal().normalized()
        w = axis.cross(u)
        base = len(verts)
        for k in range(segments):
            phi = 2 * math.pi * k / segments
            d = r * (math.cos(phi) * u + math.sin(phi) * w)
            verts += [a + d, b + d]
        for k in range(segments):
            k1 = (k + 1) % segments
            faces.append((base + 2 * k, base + 2 * k1, base + 2 * k1 + 1, base + 2 * k + 1))
    me = bpy.data.meshes.new("cylinders")
    me.from_pydata([tuple(v) for v in verts], [], faces)
    me.polygons.foreach_set("use_smooth", [True] * len(faces))
    me.update()
    add_object("cylinders", me, mat)


def add_plane(height, target, mat, half=1.0e4):
    """shimmer's infinite plane y = height as a large square."""
    cx, cy = target[0], -target[2]
    me = bpy.data.meshes.new("plane")
    me.from_pydata([(cx - half, cy - half, height), (cx + half, cy - half, height),
                    (cx + half, cy + half, height), (cx - half, cy + half, height)], [], [(0, 1, 2, 3)])
    me.update()
    add_object("plane", me, mat)


def add_light():
    light = SHOT["light"]
    if light["type"] == "sun":
        rgb = light["irradiance"]
        data = bpy.data.lights.new("sun", "SUN")
        data.angle = 0.0
    else:
        rgb = light["intensity"]
        data = bpy.data.lights.new("point", "POINT")
        data.shadow_soft_size = 0.0
    strength = max(rgb)
    data.color = [x / strength for x in rgb] if strength > 0 else (1, 1, 1)
    data.energy = strength if light["type"] == "sun" else 4 * math.pi * strength
    data.use_shadow = False
    data.cycles.cast_shadow = False
    obj = add_object(data.name, data, None)
    if light["type"] == "sun":
        # A sun shines along its local -z: its +z points towards the light.
        obj.rotation_euler = zup(light["direction"]).to_track_quat("Z", "Y").to_euler()
    else:
        obj.location = zup(light["position"])


def add_camera():
    c = SHOT["camera"]
    data = bpy.data.cameras.new("camera")
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.sensor_height = 24.0
    data.lens = 12.0 / c["tan_half_fov_y"]
    data.clip_start = 1e-4
    data.clip_end = 1e7
    obj = add_object("camera", data, None)
    right, up, back = zup(c["right"]), zup(c["up"]), -zup(c["fwd"])
    m = Matrix.Identity(4)
    for i in range(3):
        m[i][0], m[i][1], m[i][2], m[i][3] = right[i], up[i], back[i], zup(c["pos"])[i]
    obj.matrix_world = m
    bpy.context.scene.camera = obj


def configure(scene, args):
    c = SHOT["camera"]
    scene.render.engine = "CYCLES"
    scene.render.resolution_x = c["width"]
    scene.render.resolution_y = c["height"]
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    scene.render.use_motion_blur = False
    scene.render.film_transparent = False
    if args.threads > 0:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = args.threads
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = args.spp
    cy.seed = args.seed
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.max_bounces = cy.diffuse_bounces = cy.glossy_bounces = 0
    cy.transmission_bounces = cy.volume_bounces = cy.transparent_max_bounces = 0
    cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
    cy.light_sampling_threshold = 0.0  # its default ends light samples at random
    cy.blur_glossy = 0.0
    cy.caustics_reflective = cy.caustics_refractive = False
    world = bpy.data.worlds.new("black")
    world.use_nodes = False
    world.color = (0, 0, 0)
    scene.world = world
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    fmt = scene.render.image_settings
    fmt.file_format = "OPEN_EXR"
    fmt.color_mode = "RGB"
    fmt.color_depth = "32"
    fmt.exr_codec = "ZIP"
    scene.render.use_file_extension = False
    scene.render.filepath = os.path.abspath(args.out)


def main():
    args = parse_args()
    clear_scene()
    scene = bpy.context.scene
    mat = make_material()
    spheres = [list(s) for s in SHOT["spheres"]]
    for c in SHOT["capsules"]:
        spheres += [c[0:3] + [c[6]], c[3:6] + [c[6]]]
    if spheres:
        add_spheres(spheres, mat)
    if SHOT["capsules"]:
        add_cylinders(SHOT["capsules"], mat)
    for h in SHOT["planes"]:
        add_plane(h, SHOT["camera"]["target"], mat)
    add_light()
    add_camera()
    configure(scene, args)
    bpy.ops.render.render(write_still=True)
    if not os.path.isfile(scene.render.filepath):
        sys.exit("scene.py: Cycles wrote no " + scene.render.filepath)
    print("scene.py: wrote %s (%d spp)" % (scene.render.filepath, args.spp))


main()
)PY";

}  // namespace

Result<nlohmann::json> BlenderShotData(const BlenderShot& shot) {
  using R = Result<nlohmann::json>;
  if (shot.frame < 0) return R::Failure("frame " + std::to_string(shot.frame) + " must be >= 0");
  if (shot.width < 1 || shot.height < 1 || shot.width > 16384 || shot.height > 16384)
    return R::Failure("width and height must be in 1..16384, got " + std::to_string(shot.width) + "x" +
                      std::to_string(shot.height));
  if (!std::isfinite(shot.fps) || shot.fps <= 0) return R::Failure("fps must be > 0, got " + NumberText(shot.fps));
  if (shot.default_spp < 1) return R::Failure("spp must be >= 1, got " + std::to_string(shot.default_spp));
  const shading::MaterialDesc& m = shot.material;
  if (m.alpha.x != m.alpha.y)
    return R::Failure("material " + scene::MaterialSpec(m) +
                      ": anisotropic roughness is not reproduced in Blender (its tangent frame differs from "
                      "shimmer's); give an isotropic --material, e.g. " +
                      std::string(shading::NdfName(m.ndf)) + ":" + NumberText(m.alpha.x));
  nlohmann::json spheres = nlohmann::json::array(), capsules = nlohmann::json::array(),
                 planes = nlohmann::json::array();
  int index = 0;
  for (const scene::Primitive& p : shot.scene.primitives) {
    if (p.normal_map)
      return R::Failure("scene " + shot.scene.name + ": primitive " + std::to_string(index) + " has a normal map (" +
                        p.normal_map->name + "); normal maps are not exported to Blender");
    switch (p.type) {
      case scene::Primitive::Type::kSphere: spheres.push_back({p.a.x, p.a.y, p.a.z, p.radius}); break;
      case scene::Primitive::Type::kCapsule:
        capsules.push_back({p.a.x, p.a.y, p.a.z, p.b.x, p.b.y, p.b.z, p.radius});
        break;
      case scene::Primitive::Type::kPlane:
        if (p.bump_slope != 0)
          return R::Failure("scene " + shot.scene.name + ": primitive " + std::to_string(index) +
                            " is a bump-mapped plane (bump_slope " + NumberText(p.bump_slope) +
                            "); its procedural normals are not reproduced in Blender");
        planes.push_back(p.radius);
        break;
      case scene::Primitive::Type::kMesh:
        return R::Failure("scene " + shot.scene.name + ": primitive " + std::to_string(index) + " is a mesh asset (" +
                          p.mesh->file.string() + "); meshes are not exported to Blender yet");
    }
    ++index;
  }
  const shading::CameraDesc c =
      scene::CameraAt(shot.camera_path, shot.scene.rig, shot.frame, shot.fps, shot.width, shot.height);
  if (shot.scene.light.type == shading::LightType::kSg)
    return R::Failure("scene " + shot.scene.name +
                      " has a spherical-Gaussian light, which Cycles has no lamp for (an SG light is checked against "
                      "shimmer's Monte Carlo reference instead)");
  nlohmann::json light;
  if (shot.scene.light.type == shading::LightType::kDirectional)
    light = {{"type", "sun"}, {"direction", Vec(shot.scene.light.vec)}, {"irradiance", Vec(shot.scene.light.radiance)}};
  else
    light = {{"type", "point"},
             {"position", Vec(shot.scene.light.vec)},
             {"intensity", Vec(shot.scene.light.radiance)},
             {"radius", shot.scene.light.radius}};
  nlohmann::json j;
  j["scene"] = shot.scene.name;
  j["camera"] = {{"path", std::string(scene::CameraPathName(shot.camera_path))},
                 {"frame", shot.frame},
                 {"fps", shot.fps},
                 {"pos", Vec(c.pos)},
                 {"fwd", Vec(c.fwd)},
                 {"right", Vec(c.right)},
                 {"up", Vec(c.up)},
                 {"target", Vec(shot.scene.rig.target)},
                 {"tan_half_fov_y", c.tan_half_fov_y},
                 {"fov_y_deg", 360.0 / kPi * std::atan(c.tan_half_fov_y)},
                 {"width", c.width},
                 {"height", c.height}};
  j["spheres"] = spheres;
  j["capsules"] = capsules;
  j["planes"] = planes;
  j["light"] = light;
  j["material"] = {{"spec", scene::MaterialSpec(m)},
                   {"ndf", std::string(shading::NdfName(m.ndf))},
                   {"alpha", m.alpha.x},
                   {"roughness", std::sqrt(m.alpha.x)},
                   {"f0", Vec(m.f0)},
                   {"albedo", Vec(m.albedo)}};
  j["specular_only"] = shot.specular_only;
  j["default_spp"] = shot.default_spp;
  return j;
}

Result<std::string> BlenderScript(const BlenderShot& shot) {
  auto data = BlenderShotData(shot);
  if (!data) return data.failure();
  // A quote only occurs inside JSON strings, where \u0027 means the same: the
  // data cannot end the Python raw string early.
  std::string json;
  for (char ch : data->dump()) json += ch == '\'' ? std::string("\\u0027") : std::string(1, ch);
  std::string name;  // for a comment line
  for (char ch : shot.scene.name) name += ch >= 32 && ch < 127 ? ch : '?';
  std::string script =
      "# Generated by `shimmer export-blender`: shimmer's shot " + name + " (camera " +
      std::string(scene::CameraPathName(shot.camera_path)) + ", frame " + std::to_string(shot.frame) +
      ") for Blender Cycles.\n"
      "# Run: blender -b --factory-startup -P THIS.py -- --out shot.exr [--spp N] [--threads T] [--seed S]\n"
      "# Not reproduced exactly: Cycles' GGX/Beckmann masking is the separable Smith G1*G1 (shimmer's is\n"
      "# height-correlated; they differ at grazing rims), and capsules are 128-sided smooth cylinders.\n"
      "import json\n\n"
      "# --- shot ---\n"
      "SHOT = json.loads(r'''" +
      json +
      "''')\n"
      "# --- end shot ---\n";
  script += kScriptBody;
  return script;
}

}  // namespace shimmer::experiments

// Embree 3 behind RayScene (see ray_scene.h). One Embree device for the process,
// created on first use; one Embree scene per RayScene, one triangle geometry per
// mesh with the geometry ID equal to the mesh index.
#include "core/render/ray_scene.h"

#include "core/common/error.h"

#include <embree3/rtcore.h>

#include <limits>
#include <string>
#include <vector>

namespace modestack::render {
namespace {

RTCDevice shared_device()
{
    // Created once, kept for the life of the process: a device costs milliseconds
    // and frames are rendered one after another.
    static RTCDevice device = [] {
        RTCDevice created = rtcNewDevice(nullptr);
        if (created == nullptr)
            throw internal_error("cannot create the Embree device (error " +
                                 std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
        return created;
    }();
    return device;
}

} // namespace

struct RayScene::Impl {
    RTCScene scene = nullptr;
    // Unit front-side normal of every triangle, per mesh: computed here from the
    // winding rather than taken from Embree's Ng, whose sign convention is theirs.
    std::vector<std::vector<scene::Vec3>> triangle_normals;
};

RayScene::RayScene(const scene::Scene& description) : m_impl(std::make_unique<Impl>())
{
    RTCDevice device = shared_device();
    m_impl->scene = rtcNewScene(device);
    for (std::size_t mesh_index = 0; mesh_index < description.meshes.size(); ++mesh_index) {
        const scene::Mesh& mesh = description.meshes[mesh_index];
        if (mesh.indices.size() % 3 != 0)
            throw Error(ErrorKind::BadInput,
                        "scene mesh '" + mesh.name + "': index count is not a multiple of 3");
        for (std::uint32_t index : mesh.indices)
            if (index >= mesh.positions.size())
                throw Error(ErrorKind::BadInput, "scene mesh '" + mesh.name + "': vertex index out of range");
        std::vector<scene::Vec3>& normals = m_impl->triangle_normals.emplace_back();
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
            auto [p0, p1, p2] = mesh.corners(t);
            scene::Vec3 normal = scene::cross(p1 - p0, p2 - p0);
            float area2 = scene::length(normal);
            normals.push_back(area2 > 0 ? normal * (1.0f / area2) : scene::Vec3{0, 0, 1});
        }
        if (mesh.triangle_count() == 0)
            continue;
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                     RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                                     mesh.positions.size()));
        for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
            vertices[3 * i + 0] = mesh.positions[i].x;
            vertices[3 * i + 1] = mesh.positions[i].y;
            vertices[3 * i + 2] = mesh.positions[i].z;
        }
        auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                       RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                                       mesh.triangle_count()));
        for (std::size_t i = 0; i < mesh.indices.size(); ++i)
            indices[i] = mesh.indices[i];
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(m_impl->scene, geometry, static_cast<unsigned>(mesh_index));
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(m_impl->scene);
    RTCError error = rtcGetDeviceError(device);
    if (error != RTC_ERROR_NONE)
        throw internal_error("Embree failed to build the scene (error " +
                             std::to_string(static_cast<int>(error)) + ")");
}

RayScene::~RayScene()
{
    if (m_impl && m_impl->scene != nullptr)
        rtcReleaseScene(m_impl->scene);
}

bool RayScene::intersect(scene::Vec3 origin, scene::Vec3 direction, float max_distance, RayHit& hit) const
{
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit query{};
    query.ray.org_x = origin.x;
    query.ray.org_y = origin.y;
    query.ray.org_z = origin.z;
    query.ray.dir_x = direction.x;
    query.ray.dir_y = direction.y;
    query.ray.dir_z = direction.z;
    query.ray.tnear = 0;
    query.ray.tfar = max_distance;
    query.ray.mask = 0xffffffffu;
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m_impl->scene, &context, &query);
    if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return false;
    hit.distance = query.ray.tfar;
    hit.mesh_index = static_cast<int>(query.hit.geomID);
    hit.triangle_index = static_cast<int>(query.hit.primID);
    hit.geometric_normal = m_impl->triangle_normals[query.hit.geomID][query.hit.primID];
    hit.b1 = query.hit.u;  // Embree's u, v weigh the triangle's vertices 1 and 2
    hit.b2 = query.hit.v;
    return true;
}

bool RayScene::occluded(scene::Vec3 origin, scene::Vec3 direction, float max_distance) const
{
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay query{};
    query.org_x = origin.x;
    query.org_y = origin.y;
    query.org_z = origin.z;
    query.dir_x = direction.x;
    query.dir_y = direction.y;
    query.dir_z = direction.z;
    query.tnear = 0;
    query.tfar = max_distance;
    query.mask = 0xffffffffu;
    rtcOccluded1(m_impl->scene, &context, &query);
    return query.tfar == -std::numeric_limits<float>::infinity();
}

} // namespace modestack::render

#include <scanplan/scanner/embree_mesh.h>

#include <cstddef>

namespace scanplan::scanner {

RTCGeometry embreeTriangles(RTCDevice device, const kinematics::TriangleMesh& mesh) {
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 4 * sizeof(float),
                                                               mesh.vertices.size()));
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (std::size_t k = 0; k < 3; ++k)
      vertices[4 * i + k] = static_cast<float>(mesh.vertices[i](static_cast<Eigen::Index>(k)));
    vertices[4 * i + 3] = 0.0f;
  }
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles.size()));
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (std::size_t k = 0; k < 3; ++k)
      indices[3 * i + k] = static_cast<unsigned>(mesh.triangles[i](static_cast<Eigen::Index>(k)));
  }
  rtcCommitGeometry(geometry);
  return geometry;
}

}  // namespace scanplan::scanner

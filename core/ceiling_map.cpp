#include "core/ceiling_map.h"

namespace ceilpose {

PlaneMotion datum_motion(const CeilingMap& map, const CeilingLayout& layout) {
  double px = 0.0, py = 0.0, qx = 0.0, qy = 0.0;
  int n = 0;
  for (int j = 0; j < map.codes(); ++j)
    for (int i = 0; i < map.codes(); ++i) {
      const MarkerPlacement* p = map.find(i, j);
      if (p == nullptr) continue;
      px += p->x_m;
      py += p->y_m;
      qx += i * layout.grid_m;
      qy += j * layout.grid_m;
      ++n;
    }
  if (n == 0) return {};
  px /= n;
  py /= n;
  qx /= n;
  qy /= n;
  // Procrustes in the plane: the rotation that best aligns the centred
  // point sets is atan2(sum p' x q', sum p' . q').
  double cross = 0.0, dot = 0.0;
  for (int j = 0; j < map.codes(); ++j)
    for (int i = 0; i < map.codes(); ++i) {
      const MarkerPlacement* p = map.find(i, j);
      if (p == nullptr) continue;
      const double ax = p->x_m - px, ay = p->y_m - py;
      const double bx = i * layout.grid_m - qx, by = j * layout.grid_m - qy;
      cross += ax * by - ay * bx;
      dot += ax * bx + ay * by;
    }
  PlaneMotion m;
  m.rotation_rad = n >= 2 ? std::atan2(cross, dot) : 0.0;
  const double c = std::cos(m.rotation_rad), s = std::sin(m.rotation_rad);
  m.tx_m = qx - (c * px - s * py);
  m.ty_m = qy - (s * px + c * py);
  return m;
}

void move_map(const PlaneMotion& motion, CeilingMap* map) {
  for (int j = 0; j < map->codes(); ++j)
    for (int i = 0; i < map->codes(); ++i) {
      MarkerPlacement* p = map->find_mutable(i, j);
      if (p == nullptr) continue;
      motion.apply(&p->x_m, &p->y_m);
      p->yaw_rad = wrap_angle_rad(p->yaw_rad + motion.rotation_rad);
    }
}

}  // namespace ceilpose

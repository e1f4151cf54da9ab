#include "ipc/dds/dds_ceiling_markers.h"

#include "ipc/dds/dds_messages.h"

namespace ceilpose {
namespace {

constexpr int32_t kCubeList = 6;        // visualization_msgs/Marker CUBE_LIST
constexpr int32_t kTextViewFacing = 9;  // TEXT_VIEW_FACING
constexpr int32_t kAdd = 0;             // Marker actions
constexpr int32_t kDeleteAll = 3;
constexpr double kPrintThickness_m = 0.002;
constexpr double kLabelDrop_m = 0.05;  // labels just below the tiles
constexpr double kLabelHeight_m = 0.04;
constexpr char kEmpty[] = "";
constexpr char kRectanglesNs[] = "ceiling";
constexpr char kLabelsNs[] = "ceiling_codes";

template <typename Seq, typename T>
void point_at(Seq* seq, std::vector<T>* items) {
  seq->_maximum = static_cast<uint32_t>(items->size());
  seq->_length = static_cast<uint32_t>(items->size());
  seq->_buffer = items->empty() ? nullptr : items->data();
  seq->_release = false;
}

visualization_msgs_msg_dds__Marker_ blank_marker(int64_t stamp_real_ns, const char* ns, int32_t id,
                                                 int32_t type, int32_t action = kAdd) {
  visualization_msgs_msg_dds__Marker_ m{};
  DdsPose stamp_only;
  stamp_only.capture_realtime_ns = stamp_real_ns;
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ stamped;
  to_message(stamp_only, &stamped);  // the header: stamp and frame "map"
  m.header = stamped.header;
  m.ns = const_cast<char*>(ns);
  m.id = id;
  m.type = type;
  m.action = action;
  m.pose.orientation.w = 1.0;
  m.texture_resource = const_cast<char*>(kEmpty);
  m.texture.header = stamped.header;
  m.texture.format = const_cast<char*>(kEmpty);
  m.text = const_cast<char*>(kEmpty);
  m.mesh_resource = const_cast<char*>(kEmpty);
  m.mesh_file.filename = const_cast<char*>(kEmpty);
  return m;
}

}  // namespace

CeilingMarkers::CeilingMarkers(const CeilingLayout& layout, const CeilingMap& map,
                               int64_t stamp_real_ns) {
  const double z = layout.height_m;
  for (int j = 0; j < map.codes(); ++j)
    for (int i = 0; i < map.codes(); ++i) {
      const MarkerPlacement* p = map.find(i, j);
      if (p == nullptr) continue;
      double x = 0.0, y = 0.0;
      p->world_point(layout.red_centre_e_m(), 0.0, &x, &y);
      red_points_.push_back({x, y, z});
      p->world_point(layout.green_centre_e_m(), 0.0, &x, &y);
      green_points_.push_back({x, y, z});
      labels_.push_back(std::to_string(i) + "," + std::to_string(j));
    }
  const bool labelled = static_cast<int>(labels_.size()) <= kMaxLabels;
  markers_.reserve(3 + (labelled ? labels_.size() : 0));
  // First, clear what an earlier ceiling drew: a map reloaded with fewer
  // markers must not leave the old labels standing in RViz.
  markers_.push_back(blank_marker(stamp_real_ns, kEmpty, 0, 0, kDeleteAll));
  for (int k = 0; k < 2; ++k) {
    auto m = blank_marker(stamp_real_ns, kRectanglesNs, k, kCubeList);
    m.scale = {layout.rect_width_m, layout.rect_height_m, kPrintThickness_m};
    const Rgb c = k == 0 ? layout.red : layout.green;
    m.color = {c.r / 255.0f, c.g / 255.0f, c.b / 255.0f, 1.0f};
    point_at(&m.points, k == 0 ? &red_points_ : &green_points_);
    markers_.push_back(m);
  }
  if (labelled) {
    for (size_t n = 0; n < labels_.size(); ++n) {
      auto m = blank_marker(stamp_real_ns, kLabelsNs, static_cast<int32_t>(n), kTextViewFacing);
      m.pose.position = {0.5 * (red_points_[n].x + green_points_[n].x),
                         0.5 * (red_points_[n].y + green_points_[n].y), z - kLabelDrop_m};
      m.scale.z = kLabelHeight_m;
      m.color = {0.1f, 0.1f, 0.1f, 1.0f};
      m.text = labels_[n].data();
      markers_.push_back(m);
    }
  }
  point_at(&array_.markers, &markers_);
}

}  // namespace ceilpose

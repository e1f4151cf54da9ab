#pragma once
// QoS objects live only around the create call that uses them.
#include <dds/dds.h>

#include <memory>

namespace ceilpose {

struct DdsQosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using DdsQos = std::unique_ptr<dds_qos_t, DdsQosDeleter>;

inline DdsQos make_dds_qos() { return DdsQos(dds_create_qos()); }

}  // namespace ceilpose

#include "contact/contact_interfaces.hpp"

#include <algorithm>

namespace depthfem {

std::string interface_name(const std::string& a, const std::string& b) {
  return a == b ? a + " (self)" : a + "/" + b;
}

ContactInterfaces::ContactInterfaces(const std::vector<Body>& bodies, bool self_contact)
    : num_bodies_(static_cast<Index>(bodies.size())) {
  row_.assign(static_cast<size_t>(num_bodies_) * static_cast<size_t>(num_bodies_), -1);
  for (Index a = 0; a < num_bodies_; ++a) {
    for (Index b = a; b < num_bodies_; ++b) {
      if (a == b && !self_contact) continue;
      const Index row = static_cast<Index>(names_.size());
      row_[a * num_bodies_ + b] = row_[b * num_bodies_ + a] = row;
      names_.push_back(interface_name(bodies[a].name, bodies[b].name));
    }
  }
}

ContactInterfaces::Tally::Tally(const ContactInterfaces& interfaces, StepRecord& step)
    : interfaces_(interfaces),
      step_(step),
      first_(step.contact.size()),
      areas_(interfaces.names_.size(), {0.0, 0.0}) {
  for (const std::string& name : interfaces_.names_)
    step_.contact.push_back({name, Vec3::Zero(), 0, 0});
}

void ContactInterfaces::Tally::add(Index a, Index b, const Vec3& on_a, double area_of_a) {
  const size_t row = static_cast<size_t>(interfaces_.row_[a * interfaces_.num_bodies_ + b]);
  InterfaceForce& f = step_.contact[first_ + row];
  f.force += a <= b ? on_a : Vec3(-on_a);  // the force on the first body of the row
  f.magnitude += on_a.norm();
  areas_[row][a <= b ? 0 : 1] += area_of_a;
}

void ContactInterfaces::Tally::finish() {
  for (size_t row = 0; row < areas_.size(); ++row) {
    const bool self = step_.contact[first_ + row].name.ends_with(" (self)");
    step_.contact[first_ + row].area =
        self ? 0.5 * areas_[row][0] : std::max(areas_[row][0], areas_[row][1]);
  }
}

}  // namespace depthfem

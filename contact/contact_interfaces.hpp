#pragma once
/// The rows a body-to-body contact module reports per step: one per pair of bodies and, with
/// self-contact, one per body against itself.

#include <array>
#include <string>
#include <vector>

#include "core/mesh.hpp"
#include "core/step_record.hpp"

namespace depthfem {

/// The name of the interface between bodies named a and b: "a/b", or "a (self)" where a is b.
std::string interface_name(const std::string& a, const std::string& b);

/// Maps (body a, body b) to a report row. Rows are "a/b" for every a before b in the scene and,
/// with self-contact, "a (self)".
///
/// A row's force is the force on its first body, summed over the interface's pairs, and its
/// magnitude the sum of the magnitudes of the forces added (per pair, or per penetrating
/// triangle where the module nets a triangle's pairs; pairs are found from both sides: a's
/// surface inside b and b's surface inside a; both push a the same way, so the magnitude is
/// |force| where the pressure points one way, and for self-contact the force pressed across the
/// fold). The area is the larger of the two penetrated surface areas (a coarse body whose tets
/// all lie on its boundary has zero depth and catches nothing); for self-contact, where both
/// sides are the same surface, half the penetrated area.
class ContactInterfaces {
 public:
  ContactInterfaces(const std::vector<Body>& bodies, bool self_contact);

  /// Sums the pairs of one step into the rows it appends to a record.
  class Tally {
   public:
    /// Adds one pair: the force `on_a` [N] that body a receives from body b through it, and
    /// the area [m^2] of a's surface it covers.
    void add(Index a, Index b, const Vec3& on_a, double area_of_a);
    /// Writes the areas into the rows.
    void finish();

   private:
    friend class ContactInterfaces;
    Tally(const ContactInterfaces& interfaces, StepRecord& step);
    const ContactInterfaces& interfaces_;
    StepRecord& step_;
    size_t first_;
    std::vector<std::array<double, 2>> areas_;  // per row: first body's surface, second's
  };

  /// The rows' names, in order.
  const std::vector<std::string>& names() const { return names_; }

  /// Appends a zero row per interface to step.contact and returns the tally that fills them.
  Tally tally(StepRecord& step) const { return Tally(*this, step); }

 private:
  std::vector<std::string> names_;
  Index num_bodies_ = 0;
  std::vector<Index> row_;  // [a * #bodies + b] -> row, -1: none
};

}  // namespace depthfem

#include "processor.hpp"

namespace skillbus::skills {

void Processor::preempt_from(const Children& children, size_t first) {
  for (size_t i = first; i < children.size(); ++i) children[i]->preempt();
}

}  // namespace skillbus::skills

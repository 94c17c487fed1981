// Scenes as Turtle in the form SkiROS2 uses for scenes and world-model instances:
//   skiros:Cube-3 a skiros:Cube, owl:NamedIndividual ;
//       rdfs:label "cube" ; skiros:PositionX "0.1"^^xsd:float ; skiros:contain skiros:X-4 .
// Individuals (owl:NamedIndividual) become elements; typed literals become properties
// (xsd:string, float/double/decimal, int/integer/long, boolean; untyped = string);
// IRIs that name other individuals become relations. Class and property axioms in the
// file are added to the ontology. Saving writes the same form, sorted, so saving and
// loading give the same world.
#pragma once

#include <string>
#include <vector>

#include "skillbus/wm/ontology.hpp"
#include "skillbus/wm/store.hpp"

namespace skillbus::wm {

struct Scene {
  std::vector<Element> elements;
  std::vector<Relation> relations;
  std::vector<std::string> notes;  // what was skipped, for the load report
};

// Parses a scene; ontology axioms it contains go into `ontology`. Throws WmError on
// malformed Turtle or an element whose values do not fit the ontology.
Scene read_scene(const std::string& turtle, Ontology& ontology, Prefixes& prefixes, const std::string& source);
std::string write_scene(const WorldStore& store, const Prefixes& prefixes);

}  // namespace skillbus::wm

// Scenes as Turtle in the form SkiROS2 uses for scenes and world-model instances:
//   skiros:Cube-3 a skiros:Cube, owl:NamedIndividual ;
//       rdfs:label "cube" ; skiros:PositionX "0.1"^^xsd:float ; skiros:contain skiros:X-4 .
// Individuals (owl:NamedIndividual) become elements; typed literals become properties
// (xsd:string, float/double/decimal, int/integer/long, boolean; untyped = string);
// IRIs that name other individuals become relations. Class and property axioms in the
// file are added to the ontology. Saving writes the same form, sorted, with the scene's
// other triples (Scene::extra) after the elements, so load, save, load loses none.
#pragma once

#include <string>
#include <vector>

#include "skillbus/wm/ontology.hpp"
#include "skillbus/wm/store.hpp"

namespace skillbus::wm {

struct Scene {
  std::vector<Element> elements;
  std::vector<Relation> relations;
  std::vector<std::string> notes;  // what was set aside, for the load report
  // Every triple that is not an element's type, label, value or relation to another
  // individual of the scene (class and property axioms, the owl:Ontology header,
  // relations to templates and classes, a second type): saved back with the scene, so
  // load, save, load keeps every triple.
  std::vector<Triple> extra;
};

// Parses a scene; ontology axioms it contains go into `ontology`. Throws WmError on
// malformed Turtle or an element whose values do not fit the ontology.
Scene read_scene(const std::string& turtle, Ontology& ontology, Prefixes& prefixes, const std::string& source);
// Throws WmError naming every element type of `scene` that `ontology` does not know, with
// (some of) its elements, at once: the store would stop at the first, and a scene written
// for ontologies that are not loaded should show all it needs.
void check_scene_types(const Scene& scene, const Ontology& ontology, const std::string& source);
// The scene's triples (every element: its types, label, properties and relations; then
// `extra`), full IRIs; write_scene writes them as Turtle.
std::vector<Triple> scene_triples(const WorldStore& store, const Prefixes& prefixes,
                                  const std::vector<Triple>& extra = {});
std::string write_scene(const WorldStore& store, const Prefixes& prefixes, const std::vector<Triple>& extra = {});

}  // namespace skillbus::wm

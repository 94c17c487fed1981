#include "skillbus/sim/script.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace skillbus::sim {

using scene::SceneError;

std::vector<ScriptStep> load_script(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the script file");
  std::stringstream ss;
  ss << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ss.str());
  } catch (const nlohmann::json::exception& e) {
    throw SceneError(path + ": not valid JSON: " + e.what());
  }
  std::vector<ScriptStep> out;
  if (!j.is_object() || !j.contains("steps") || !j["steps"].is_array())
    throw SceneError(path + ": needs {\"steps\": [...]}");
  size_t i = 0;
  try {
    for (const auto& s : j["steps"]) {
      const std::string where = path + ": steps[" + std::to_string(i++) + "]";
      if (!s.contains("at_s") || !s["at_s"].is_number()) throw SceneError(where + " needs a number at_s");
      const int64_t at = static_cast<int64_t>(std::llround(s["at_s"].get<double>() * 1e9));
      const std::string robot = s.value("robot", "");
      if (s.contains("arm")) {
        ScriptStep st;
        st.at_ns = at;
        st.robot = robot;
        st.is_arm = true;
        const auto& a = s["arm"];
        st.arm.id = a.value("id", "");
        st.arm.joints = a.at("joints").get<std::vector<std::string>>();
        for (const auto& p : a.at("points")) {
          Waypoint w;
          w.t_ns = static_cast<int64_t>(std::llround(p.at(0).get<double>() * 1e9));
          w.q = p.at(1).get<std::vector<double>>();
          if (p.size() > 2) w.qd = p.at(2).get<std::vector<double>>();  // [t, q, qd]: velocities given
          st.arm.points.push_back(std::move(w));
        }
        out.push_back(std::move(st));
      }
      if (s.contains("gripper")) {
        ScriptStep st;
        st.at_ns = at;
        st.robot = robot;
        const auto& g = s["gripper"];
        st.gripper = GripperCommand{g.value("id", ""), g.at("width").get<double>(), g.value("speed", 0.1),
                                    g.value("force_limit", 20.0)};
        out.push_back(std::move(st));
      }
      if (s.contains("attach")) {  // {"id": ..., "attach": true|false, "object": NAME}
        ScriptStep st;
        st.at_ns = at;
        st.robot = robot;
        st.is_attach = true;
        const auto& a = s["attach"];
        st.attach = AttachCommand{a.value("id", ""), a.value("attach", true), a.value("object", "")};
        out.push_back(std::move(st));
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw SceneError(path + ": steps[" + std::to_string(i - 1) + "]: " + e.what());
  }
  std::stable_sort(out.begin(), out.end(), [](const ScriptStep& a, const ScriptStep& b) { return a.at_ns < b.at_ns; });
  return out;
}

}  // namespace skillbus::sim

#include "sim/mujoco_model.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

namespace kuavo::sim {
namespace {

namespace fs = std::filesystem;

bool read_text(const fs::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  out = s.str();
  return true;
}

std::string number(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

}  // namespace

std::string published_mjcf_path(const model::Model& model) {
  // The tables name their URDF: <model>/urdf/biped_sXX.urdf; the MJCF is <model>/xml/biped_sXX.xml.
  const fs::path urdf = fs::path(model.tables->source_urdf);
  const fs::path dir = urdf.parent_path().parent_path();
  return (fs::path(KUAVO_SIM_SHARED_DIR) / "robot" / dir / "xml" / urdf.filename().replace_extension(".xml")).string();
}

bool generate_mjcf(const model::Model& model, const MjcfOptions& options, std::string& xml, std::string& error) {
  const fs::path source = published_mjcf_path(model);
  if (!read_text(source, xml)) {
    error = "cannot read Leju's MJCF '" + source.string() + "'";
    return false;
  }
  auto fail = [&](const std::string& what) {
    error = source.string() + ": " + what;
    return false;
  };
  xml = std::regex_replace(xml, std::regex(R"( actuatorfrcrange="[^"]*")"), "");
  // A closing quote glued to the next attribute name: `type="hinge"pos=` (s45, line 158).
  xml = std::regex_replace(xml, std::regex(R"re(="([^"]*)"([A-Za-z_]))re"), R"(="$1" $2)");

  const std::regex meshdir(R"re(meshdir="([^"]*)")re");
  std::smatch m;
  if (!std::regex_search(xml, m, meshdir)) return fail("no meshdir in <compiler>");
  const fs::path mesh_dir = fs::weakly_canonical(source.parent_path() / m[1].str());
  xml = std::regex_replace(xml, meshdir, "meshdir=\"" + mesh_dir.string() + "/\"", std::regex_constants::format_first_only);
  const std::size_t compiler = xml.find("<compiler ");
  if (compiler == std::string::npos) return fail("no <compiler>");
  xml.insert(compiler + 10, "autolimits=\"true\" ");

  // Only the torso's mass changes: the others sum to what the published links weigh.
  const std::regex mass(R"re(mass="([^"]*)")re");
  double others_kg = 0.0;
  const std::size_t base = xml.find("<body name=\"base_link\"");
  if (base == std::string::npos) return fail("no base_link body");
  std::size_t base_mass_at = std::string::npos, base_mass_len = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), mass); it != std::sregex_iterator(); ++it) {
    const auto at = static_cast<std::size_t>(it->position(0));
    if (at > base && base_mass_at == std::string::npos) {
      base_mass_at = at, base_mass_len = static_cast<std::size_t>(it->length(0));
    } else {
      others_kg += std::stod((*it)[1].str());
    }
  }
  if (base_mass_at == std::string::npos) return fail("no base_link inertial mass");
  const double base_kg = model.total_mass_kg - others_kg;
  if (!(base_kg > 0.0)) return fail("the model's total mass leaves no positive torso mass");
  xml.replace(base_mass_at, base_mass_len, "mass=\"" + number(base_kg) + "\"");

  // The simulator's own settings, right after <compiler .../>.
  const std::size_t after_compiler = xml.find("/>", compiler);
  if (after_compiler == std::string::npos) return fail("<compiler> not closed");
  const std::string mu = number(options.friction_coefficient);
  std::string added = "\n  <option timestep=\"" + number(options.timestep_s) + "\" gravity=\"0 0 " +
                      number(options.gravity ? -model::kGravity_m_s2 : 0.0) + "\">";
  if (!options.contact) added += "<flag contact=\"disable\"/>";
  // Torsional and rolling friction: MuJoCo's defaults (condim 3 ignores them).
  added += "</option>\n  <default><geom friction=\"" + mu + " 0.005 0.0001\"/></default>";
  xml.insert(after_compiler + 2, added);
  const std::size_t world = xml.find("<worldbody>");
  if (world == std::string::npos) return fail("no <worldbody>");
  xml.insert(world + 11, "\n    <geom name=\"floor\" type=\"plane\" size=\"0 0 0.05\"/>");
  return true;
}

}  // namespace kuavo::sim

#include "proto/radiosity_params.h"

namespace lf {

void ToProto(const RadiositySettings& s, lightfarm::v1::RadiosityParams* out) {
    out->set_patches(s.patches);
    out->set_patch_size(s.patch_size);
    out->set_solver(s.solver);
    out->set_tolerance(s.tolerance);
    out->set_max_iterations(s.max_iterations);
    out->set_display(s.display);
    out->set_sweep_tasks(s.sweep_tasks);
    out->set_max_patches(s.max_patches);
}

RadiositySettings FromProto(const lightfarm::v1::RadiosityParams& p) {
    RadiositySettings s{p.patches(),   p.patch_size(),     p.solver(),
                        p.tolerance(), p.max_iterations(), p.display()};
    if (p.sweep_tasks() != 0) s.sweep_tasks = p.sweep_tasks();
    s.max_patches = p.max_patches();
    return s;
}

}  // namespace lf

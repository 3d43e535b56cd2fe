// Private: the factories behind the integrator registry (integrators/registry.cpp).
#pragma once

#include <memory>

#include "integrators/integrator.hpp"

namespace pumasim::detail {
std::unique_ptr<Integrator> make_euler(const IntegratorOptions&);
std::unique_ptr<Integrator> make_rk4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ab2(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ab3(const IntegratorOptions&);
std::unique_ptr<Integrator> make_ab4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_ab2(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_ab3(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_ab4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_etd_rk4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_arkode_erk(const IntegratorOptions&);
std::unique_ptr<Integrator> make_arkode_dirk(const IntegratorOptions&);
std::unique_ptr<Integrator> make_arkode_imex(const IntegratorOptions&);
std::unique_ptr<Integrator> make_cvode_bdf(const IntegratorOptions&);
std::unique_ptr<Integrator> make_cvode_adams(const IntegratorOptions&);
std::unique_ptr<Integrator> make_moreau_jean(const IntegratorOptions&);
std::unique_ptr<Integrator> make_moreau_jean_075(const IntegratorOptions&);
std::unique_ptr<Integrator> make_odeint_dopri5(const IntegratorOptions&);
std::unique_ptr<Integrator> make_odeint_rosenbrock4(const IntegratorOptions&);
std::unique_ptr<Integrator> make_odeint_rodas4p(const IntegratorOptions&);
}  // namespace pumasim::detail

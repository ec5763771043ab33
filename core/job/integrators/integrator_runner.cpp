#include "core/job/integrators/integrator_runner.h"

#include "core/job/integrators/gpt_runner.h"
#include "core/job/integrators/pt_runner.h"
#include "core/job/integrators/tgpt_runner.h"

namespace gdvr {

Expected<std::unique_ptr<IntegratorRunner>> make_integrator_runner(const JobSpec& job, std::vector<int> job_frames) {
  auto upcast = [](auto made) -> Expected<std::unique_ptr<IntegratorRunner>> {
    if (!made.ok()) return made.status();
    return std::unique_ptr<IntegratorRunner>(std::move(made.value()));
  };
  switch (job.integrator) {
    case Integrator::kPt: return std::unique_ptr<IntegratorRunner>(new PtRunner());
    case Integrator::kGpt: return upcast(GptRunner::create(job));
    case Integrator::kTgpt: return upcast(TgptRunner::create(job, std::move(job_frames)));
  }
  return invalid_argument("job.integrator: not one of " + enum_name_list(kIntegratorNames));
}

}  // namespace gdvr

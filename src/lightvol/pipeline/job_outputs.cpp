// The outputs of a batch checked against each other and against its inputs (build_job.h).
#include <string>
#include <unordered_map>
#include <vector>

#include <lightvol/core/path.h>
#include <lightvol/pipeline/build_job.h>

namespace lightvol {

Status refuse_clashing_outputs(const std::vector<BuildJob*>& jobs, const BatchFiles& files) {
  // No two jobs write one file: each output's identity, and the line of the job that writes it.
  std::unordered_map<std::string, int> written;
  for (BuildJob* job : jobs) {
    if (!job->refused.empty()) continue;
    const std::string* const paths[2] = {&job->options.out_path, &job->options.report_path};
    std::string identity[2];
    for (int k = 0; k < 2 && job->refused.empty(); ++k) {
      identity[k] = file_identity(*paths[k]);
      if (const auto earlier = written.find(identity[k]); earlier != written.end())
        job->refused = job->where + ": " + *paths[k] + ": also an output of line " +
                       std::to_string(earlier->second) + "; give each job its own out (and report)";
    }
    if (job->refused.empty())
      for (const std::string& id : identity) written.emplace(id, job->line);
  }
  // No output replaces an input: each input's identity, and what reads it.
  std::unordered_map<std::string, std::string> read;
  read.emplace(file_identity(files.jobs_path), "the jobs file");
  for (const BuildJob* job : jobs)
    if (job->refused.empty())
      for (const auto& [key, path] : build_input_files(job->options))
        read.emplace(file_identity(path), path + ", an input of line " + std::to_string(job->line) +
                                              " (key '" + key + "')");
  for (BuildJob* job : jobs) {
    if (!job->refused.empty()) continue;
    for (const std::string* out : {&job->options.out_path, &job->options.report_path})
      if (const auto input = read.find(file_identity(*out)); input != read.end()) {
        job->refused = job->where + ": " + *out + ": is also " + input->second +
                       "; an output may not replace an input";
        break;
      }
  }
  if (files.results_path.empty()) return {};
  const std::string results = file_identity(files.results_path);
  const std::string named = "BatchFiles::results_path " + files.results_path;
  if (const auto input = read.find(results); input != read.end())
    return Error{named + ": is also " + input->second + "; an output may not replace an input"};
  if (const auto output = written.find(results); output != written.end())
    return Error{named + ": is also an output of line " + std::to_string(output->second) +
                 "; give the results their own file"};
  return {};
}

}  // namespace lightvol

#pragma once

#include <string>

namespace rovermap::campaign {

/// Options of `rovermap campaign` (config section `campaign.`): what each Slurm task asks for.
struct CampaignOptions {
  int cpus_per_task = 2;        ///< [cores] per replay task (the mapper reads the next frame ahead)
  int memory_mb = 4096;         ///< [MB] per replay task (sbatch --mem)
  int time_limit_min = 0;       ///< [min] per task (sbatch --time); 0 = the partition's
  std::string partition;        ///< sbatch --partition; "" = the cluster's default
  std::string account;          ///< sbatch --account; "" = the user's default
  int mosaic_tasks = 4;         ///< [tasks] array tasks fusing the mosaic's rows of tiles
  int mosaic_memory_mb = 2048;  ///< [MB] per mosaic task (co-registration, a part, assembly)
};

}  // namespace rovermap::campaign

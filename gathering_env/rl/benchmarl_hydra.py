"""BenchMARL's own command line (hydra configs) with the gathering tasks added.

    python -m gathering_env.rl.benchmarl_hydra algorithm=mappo task=gathering/env1 \\
        task.reward_scope=team experiment.max_n_frames=480000 experiment.loggers=[csv]

is ``python benchmarl/run.py ...`` (BenchMARL's ``hydra_experiment``: every algorithm, model and
experiment option of its yaml configs) after registering ``gathering/env1`` .. ``env3``
(``gathering_env.rl.benchmarl_task``) and adding their yaml files (``conf/task/gathering/``) to
hydra's search path.
"""

from __future__ import annotations

import sys

from gathering_env.rl.benchmarl_task import CONFIG_DIR, register


def main(argv: list[str] | None = None) -> None:
    from benchmarl.run import hydra_experiment

    register()
    args = list(sys.argv[1:] if argv is None else argv)
    if not any(a.startswith("hydra.searchpath=") for a in args):
        args.append(f"hydra.searchpath=[file://{CONFIG_DIR}]")
    sys.argv = [sys.argv[0], *args]
    hydra_experiment()


if __name__ == "__main__":
    main()

"""The house's infrastructure, below every physics module: input rules (``rule``, ``validation``), safe
writes (``output``), executors and BLAS threads (``executors``) and progress lines (``progress``).
Nothing here imports the physics."""

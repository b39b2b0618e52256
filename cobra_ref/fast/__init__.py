"""The fast wing: the reference step's parts, batched and warm-started (``cobra_ref.fast.stepper``);
tests hold every part equal to the readable one."""

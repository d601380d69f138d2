"""The falsifier (``sse-cosim falsify``): an adversarial search over what the assumptions
leave free, for the world that breaks the guarantee."""

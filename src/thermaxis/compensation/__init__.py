"""From a fitted model to a machine: the model record, the runtime compensator, controller exports, the Structured Text block, ISO 230-2 and the held-out evidence."""

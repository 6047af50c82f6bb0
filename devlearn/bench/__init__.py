"""Speed measurements behind ``devlearn bench`` (figures, never asserted): the infant, the
environments, the physics ceiling, the learner and the commands' start-up."""

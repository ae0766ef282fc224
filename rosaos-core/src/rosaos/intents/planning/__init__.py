"""What to do about a sentence: the plan a task carries, follow-ups, notices, timer turns.

- ``plan``: the ``rosaos-plan`` block (:class:`Plan`), shared by the kernel's and the process's
  offline models;
- ``followups``: "X, then Y" and "X, and when you find someone, Y";
- ``notice_plan``: the answer to a ``[Device notice]``;
- ``timer_plan``: set, list and cancel timers; carry out a fired one.
"""

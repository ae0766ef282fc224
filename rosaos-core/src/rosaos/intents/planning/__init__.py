"""What to do about a sentence: follow-ups, notices, timer turns (the plan is :mod:`rosaos.events.plan`).

- ``follow_ups``: "X, then Y" and "X, and when you find someone, Y";
- ``notice_plan``: the answer to a device notice;
- ``timer_plan``: set, list and cancel timers; carry out a fired one.
"""

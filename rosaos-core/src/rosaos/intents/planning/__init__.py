"""What to do about a sentence: follow-ups (the plan is :mod:`rosaos.events.plan`).

- ``follow_ups``: "X, then Y" and "X, and when you find someone, Y".

The answer to a device notice is :mod:`rosaos.notices.notice_plan`; timer turns are :mod:`rosaos.timers.timer_turn`.
"""

"""What a sentence means in this world: matching, readings, rephrasings, guesses, refusals.

- ``matching``: :class:`IntentMatcher`, sentence → :class:`MatchResult` (the entry point);
- ``readings``: one clause's reading (tool calls per device, or a question / refusal);
- ``match_result``: readings → :class:`MatchResult` and its :class:`ProcessPlan` s;
- ``generalize``, ``rephrase``, ``fuzzy``: negations, everyday phrasings, close guesses;
- ``unknown_names``: a device name the world does not have is refused naming what exists;
- ``ranges``: a number no template takes is refused by name.
"""

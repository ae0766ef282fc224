"""The local-intent engine's replies, per language (``[models] language``); English is the fallback.

Replies are short because they may be spoken aloud. ``{clause}`` is the user's own command
("turn on the kitchen light"), which reads naturally after "Done:" in any language and spares
the engine from conjugating verbs.
"""

from __future__ import annotations

from collections.abc import Sequence

PHRASES: dict[str, dict[str, str]] = {
    "en": {
        "ack": "On it: {clause}.",
        "ack_question": "Checking the {device}.",
        "done": "Done: {clause}.",
        # Quoted, not "I couldn't {clause}": a clause is often no verb ("next song", "a bit louder").
        "failure": 'Sorry, "{clause}" failed: {error}',
        "failure_question": "Sorry, I couldn't check the {device}: {error}",
        "yes": "Yes, the {device} is {state}.",
        "no": "No, the {device} is {state}.",
        "no_not": "No, the {device} is not {state}.",
        "readout": "The {device}: {result}.",
        "clarify": "Which one do you mean: {options}?",
        "unknown": 'I don\'t know "{phrase}". I can do that with: {options}.',
        "unknown_alone": 'I don\'t know "{phrase}", and no device here can do that.',
        "unsupported": "The {device} can't do that.",
        "bad_number": "I can't do that: {value} is not a value the {device} takes there. Nothing was changed.",
        "no_match": 'Sorry, I didn\'t understand "{text}". Devices I can control: {devices}.',
        "did_you_mean": "Did you mean: {suggestion}?",
        "negated": "All right, I won't {clause}. Nothing was changed.",
        "launch_refused": "I couldn't start that: {reason}",
        "callback_failed": "Sorry, that didn't work ({status}): {error}",
        "callback_done": "Done.",
        "device_notice": "Noted: {message}",
        "error": "Something went wrong: {message}",
        "no_tool": "the tool {tool} of {device} is not available to this process (it has: {tools})",
        "or": "or",
    },
    "fr": {
        "ack": "C'est parti : {clause}.",
        "ack_question": "Je vérifie : {device}.",
        "done": "C'est fait : {clause}.",
        "failure": "Désolé, échec de « {clause} » : {error}",
        "failure_question": "Désolé, impossible de vérifier {device} : {error}",
        "yes": "Oui, {device} : {state}.",
        "no": "Non, {device} : {state}.",
        "no_not": "Non, {device} n'est pas {state}.",
        "readout": "{device} : {result}.",
        "clarify": "Lequel voulez-vous dire : {options} ?",
        "unknown": "Je ne connais pas « {phrase} ». Je peux le faire avec : {options}.",
        "unknown_alone": "Je ne connais pas « {phrase} », et aucun appareil ici ne sait le faire.",
        "unsupported": "{device} ne sait pas faire ça.",
        "bad_number": "Impossible : {device} n'accepte pas la valeur {value} ici. Rien n'a changé.",
        "no_match": "Désolé, je n'ai pas compris « {text} ». Appareils disponibles : {devices}.",
        "did_you_mean": "Vouliez-vous dire : {suggestion} ?",
        "negated": "D'accord, je ne le fais pas : {clause}. Rien n'a changé.",
        "launch_refused": "Impossible de lancer : {reason}",
        "callback_failed": "Désolé, ça n'a pas marché ({status}) : {error}",
        "callback_done": "C'est fait.",
        "device_notice": "Noté : {message}",
        "error": "Une erreur est survenue : {message}",
        "no_tool": "l'outil {tool} de {device} n'est pas disponible dans ce processus (il a : {tools})",
        "or": "ou",
    },
}

# Words that join two commands in one sentence ("turn on the lamp and play some jazz").
CONJUNCTIONS: dict[str, tuple[str, ...]] = {
    "en": ("and then", "and", "then", "also"),
    "fr": ("et puis", "et ensuite", "et", "puis", "ensuite"),
    "de": ("und dann", "und", "dann"),
    "es": ("y luego", "y", "luego"),
    "it": ("e poi", "e", "poi"),
    "nl": ("en dan", "en", "dan"),
    "pt": ("e depois", "e", "depois"),
}


# Words that stand for the device of the previous command ("undock the turtlebot and drive it
# forward"). Only where object pronouns are separate words that are never articles: French "la",
# Spanish "lo" and Dutch "het" are also articles or clitics, so those languages rely on the
# device being left out instead ("... et avance d'un mètre"), which works in every language.
PRONOUNS: dict[str, frozenset[str]] = {
    "en": frozenset({"it", "him", "her", "them"}),
}


# Words that make "the lights" mean every one of them. HA's own "all" templates need an extra
# word ("partout"), and HA's "toutes les lumières" means "here"; rosaOS has no "here", so "all"
# means the whole world.
ALL_WORDS: dict[str, frozenset[str]] = {
    "en": frozenset({"all", "every", "each"}),
    "fr": frozenset({"tous", "toutes", "tout", "toute", "chaque"}),
    "de": frozenset({"alle", "allen", "jede", "jeden"}),
    "es": frozenset({"todos", "todas", "cada"}),
    "it": frozenset({"tutti", "tutte", "ogni"}),
    "nl": frozenset({"alle", "elke"}),
    "pt": frozenset({"todos", "todas", "cada"}),
}


# Everyday words for a kind of device: a device whose kind is the key also answers to these
# ("the pup" for a robot dog). One way only: a lamp is a light, but not every light is a lamp.
KIND_SYNONYMS: dict[str, dict[str, tuple[str, ...]]] = {
    "en": {
        "dog": ("pup", "puppy", "doggy", "doggie"),
        "robot dog": ("robodog", "robot puppy", "robot"),
        "robot": ("bot",),
        "lamp": ("light",),
        "bulb": ("light",),
        "speaker": ("music",),
    },
}


# Answers that confirm a "Did you mean …?" question.
YES_WORDS: dict[str, frozenset[str]] = {
    "en": frozenset(
        {"yes", "yeah", "yep", "yes please", "sure", "correct", "right", "exactly", "do it", "ok", "okay"}
    ),
    "fr": frozenset({"oui", "ouais", "oui merci", "exactement", "d'accord", "vas-y"}),
}


def confirms(text: str, language: str) -> bool:
    """Whether ``text`` is a plain yes in ``language`` ("yes", "yes please", "sure.")."""
    words = YES_WORDS.get(language.split("-")[0], YES_WORDS["en"])
    return " ".join(text.lower().strip(" .!,").replace(",", " ").split()) in words


def kind_synonyms(language: str, kind: str) -> tuple[str, ...]:
    """Everyday synonyms of the device kind ``kind`` ("dog" → "pup") in ``language``."""
    return KIND_SYNONYMS.get(language.split("-")[0], {}).get(kind, ())


def says_all(text: str, language: str) -> bool:
    """Whether ``text`` says "all" in ``language`` ("turn off all the lights")."""
    words = ALL_WORDS.get(language.split("-")[0], ALL_WORDS["en"])
    return any(word in words for word in text.lower().replace("'", " ").split())


def phrase(language: str, key: str, **fields: str) -> str:
    """The reply ``key`` in ``language`` (English when it has no translation), filled with ``fields``."""
    table = PHRASES.get(language.split("-")[0], PHRASES["en"])
    template = table.get(key, PHRASES["en"][key])
    return template.format(**fields)


def join_options(items: Sequence[str], language: str) -> str:
    """``a, b or c`` in ``language``."""
    if len(items) <= 1:
        return "".join(items)
    return f"{', '.join(items[:-1])} {phrase(language, 'or')} {items[-1]}"


def pronouns(language: str) -> frozenset[str]:
    """Words that refer back to the device of the previous command in ``language`` (may be empty)."""
    return PRONOUNS.get(language.split("-")[0], frozenset())


def conjunctions(language: str) -> tuple[str, ...]:
    """Words that separate two commands in ``language``; the comma works in every language."""
    return CONJUNCTIONS.get(language.split("-")[0], CONJUNCTIONS["en"])

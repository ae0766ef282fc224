"""Login codes: single use, ten minutes, and only a hash is kept."""

from __future__ import annotations

from rosaos.kernel.api.login_codes import CODE_LIFETIME, MAX_LIVE_CODES, LoginCodes, login_url


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_a_code_works_once() -> None:
    codes = LoginCodes()
    code = codes.mint()
    assert codes.redeem(code) is True
    assert codes.redeem(code) is False


def test_a_code_expires_after_ten_minutes() -> None:
    clock = Clock()
    codes = LoginCodes(clock=clock)
    early, late = codes.mint(), codes.mint()
    clock.now += CODE_LIFETIME - 1
    assert codes.redeem(early) is True
    clock.now += 2
    assert codes.redeem(late) is False


def test_codes_are_independent_and_unguessable() -> None:
    codes = LoginCodes()
    first, second = codes.mint(), codes.mint()
    assert first != second
    assert len(first) >= 32
    assert codes.redeem("") is False
    assert codes.redeem(first[:-1]) is False
    assert codes.redeem(second) is True
    assert codes.redeem(first) is True


def test_only_a_bounded_number_of_codes_stay_live() -> None:
    codes = LoginCodes()
    oldest = codes.mint()
    for _ in range(MAX_LIVE_CODES):
        codes.mint()
    assert codes.redeem(oldest) is False


def test_codes_are_not_kept_in_clear() -> None:
    codes = LoginCodes()
    code = codes.mint()
    assert code not in repr(vars(codes))


def test_login_url_puts_the_code_in_the_fragment() -> None:
    assert login_url("http://127.0.0.1:8765/", "abc") == "http://127.0.0.1:8765/#login=abc"

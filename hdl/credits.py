"""The output queue's credits: how many more positions the core may admit.

A position admitted now puts a word (or a retire without one) into the output queue many
clocks later, so the admission counts what the queue can still take instead of asking it:
a credit per free word, taken by each admission and given back when a word leaves the
queue or a position retires without one. Only its flag, "one more fits", reaches the
decision (:mod:`.core`), from registers.
"""

from dataclasses import dataclass

from amaranth.hdl import Mux, Signal, Value

from .common import pipe

__all__ = ["CreditFlag", "credit_flag"]


@dataclass(frozen=True)
class CreditFlag:
    """The flag the admission's decision reads (``flag``) and, with R = 1, the same a
    clock earlier (``early``, for a register by the decision that combines it with other
    conditions; None with R >= 2)."""

    flag: Value
    early: Value | None


def credit_flag(m, depth, rounds, taken_now, popped, retired):
    """The flag the admission's decision reads: the output queue of ``depth`` words is sure
    to take one more position (a :class:`CreditFlag`).

    ``taken_now`` is the decision a clock late (a credit taken), ``popped`` a word leaving
    the queue, ``retired`` a position retiring without a word.

    Both sums (with and without the credit taken) are formed beside the admission, which
    then only chooses between them: the decision is the longest logic of the core, and an
    adder behind it cost 11 ns on ECP5 (even as a register, in front of one adder of
    returned minus taken: census 9x9, 7.5 ns). The flag is registered from the counter
    itself, a clock late, so no comparison follows the sums.

    The credits coming back are counted two clocks late (which is only more cautious,
    ``plan_timing.CREDIT_RETURN``), from registers at both ends: the queue's read and the
    L/R check's retire are registered apart (their logic into one sum was three LUTs from
    the queue's r_rdy, 6.84 ns, census 5x5 box at 1280 x 720, R = 1; through the FIFO's
    read, census 9x9: 9.6 ns), and their sum is registered as itself and less the credit a
    position takes, so that the counter's two sums are one adder each, side by side (one
    adder behind the other: 6.84 ns, the same core on another placement).
    """
    credits = Signal(range(depth + 1), init=depth)
    has_credit = Signal(init=1)
    popped = pipe(m, popped, 1, "credit_popped", reset=True)
    retired = pipe(m, retired, 1, "credit_retired", reset=True)
    returning = Signal(2)
    m.d.comb += returning.eq(popped + retired)
    back = Signal(2, name="credits_back")
    back_less_one = Signal(range(-1, 2), name="credits_back_less_one", init=-1)
    m.d.sync += [back.eq(returning), back_less_one.eq(returning - 1)]
    kept = Signal(range(depth + 3), name="credits_kept")
    taken = Signal(range(-1, depth + 2), name="credits_taken")
    m.d.comb += [kept.eq(credits + back), taken.eq(credits + back_less_one)]
    m.d.sync += [credits.eq(Mux(taken_now, taken, kept)),
                 has_credit.eq(_has_room(credits, _unseen_decisions(rounds)))]
    if rounds > 1:
        return CreditFlag(has_credit, None)
    # With R = 1 the flag crosses from the credits (by the output) to the decision (by the
    # input) through a copy by the decision, a clock later: the flag straight into the
    # decision and the row counter was census 5x5 box's critical path at 1280 x 720
    # (8.32 ns).
    return CreditFlag(pipe(m, has_credit, 1, "has_credit_near", reset=True), has_credit)


def _unseen_decisions(rounds):
    """Admissions that the credit flag a decision reads cannot have counted yet.

    A decision reaches the credits a clock later (``taken_now``), the credits the flag a
    clock after that. With R >= 2 decisions are two clocks apart or more, so one is
    unseen; with R = 1 one per clock, and the flag's copy by the decision makes three.
    """
    return 1 if rounds > 1 else 3


def _has_room(credits, unseen):
    """Whether the output queue is sure to take the word of one more position: after the
    ``unseen`` decisions not counted yet, each taking at most one credit, one is left."""
    return credits >= unseen + 1

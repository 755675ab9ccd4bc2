#include "symbolic/point_evaluator.hpp"

namespace mbsgen::detail {

cln::cl_N PointEvaluator::run(const ProgramTape::Code& code) {
  using Op = ProgramTape::Op;
  stack_.clear();
  for (const ProgramTape::Instruction& in : code) {
    switch (in.op) {
      case Op::constant:
        stack_.push_back(tape_->constants[in.arg]);
        break;
      case Op::variable:
        stack_.push_back(variable(in.arg));
        break;
      case Op::definition:
        stack_.push_back(values_[in.arg]);
        break;
      case Op::add:
      case Op::mul: {
        // As GiNaC::numeric's sum = 0, sum += x (product = 1, product *= x): the same roundings.
        const std::size_t first = stack_.size() - in.arg;
        cln::cl_N r = in.op == Op::add ? 0 : 1;
        for (std::size_t i = first; i < stack_.size(); ++i) r = in.op == Op::add ? r + stack_[i] : r * stack_[i];
        stack_.resize(first);
        stack_.push_back(std::move(r));
        break;
      }
      case Op::power: {
        const GiNaC::numeric exponent(stack_.back());
        stack_.pop_back();
        const GiNaC::numeric base(stack_.back());
        stack_.pop_back();
        const GiNaC::numeric r = exponent.is_integer() ? base.power(exponent)
                                                       : GiNaC::ex_to<GiNaC::numeric>(base.evalf()).power(exponent);
        stack_.push_back(r.to_cl_N());
        break;
      }
      case Op::function: {
        const ex& node = tape_->functions[in.arg];
        const std::size_t first = stack_.size() - node.nops();
        GiNaC::exvector args;
        args.reserve(node.nops());
        for (std::size_t i = first; i < stack_.size(); ++i) args.push_back(GiNaC::numeric(stack_[i]));
        stack_.resize(first);
        const auto& f = GiNaC::ex_to<GiNaC::function>(node);
        // CLN's exp(1e9999) = 1 and sin(1e50) = 0: refused (EvaluationError), as in checked_evalf.
        const auto fixed = checked_subs_impl::check_function(f.get_name(), args, node);
        stack_.push_back(float_of(fixed ? *fixed : GiNaC::ex(GiNaC::function(f.get_serial(), args))).to_cl_N());
        break;
      }
      case Op::other:
        stack_.push_back(float_of(tape_->others[in.arg]).to_cl_N());
        break;
    }
  }
  return stack_.back();
}

}  // namespace mbsgen::detail

// Names the API defines (docs/openapi.yaml): the job states. The DashboardContract tests
// (tests/unit/common/dashboard_contract_test.cpp) check them, and every state and path the
// page names, against the contract.

export const JOB_STATES = ['queued', 'running', 'paused', 'completed', 'failed', 'canceled'];
export const FINISHED = new Set(['completed', 'failed', 'canceled']);
